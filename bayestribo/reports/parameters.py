"""Typed notebook parameters: read the parameters cell, check values before any cell runs.

A report notebook's parameters cell holds annotated assignments::

    max_steps: int = 20000  # ceiling on the steps per ensemble
    run_path: str | None = None  # run file; None: the bundled run

The annotation is the parameter's type. :func:`parameter_specs` reads name, type,
default and comment of every line; :func:`check_value` checks a value against the type
(an ``int`` is a valid ``float``, a ``bool`` is not an ``int``), so that
``--param max_steps=5k`` is refused at once with the parameter's name and the type it
expects, instead of failing inside a cell minutes later.

Types understood: ``int``, ``float``, ``str``, ``bool``, ``None``, ``Any``, ``list``,
``dict``, ``list[T]``, ``dict[K, V]`` and unions ``A | B``. A plain assignment (no
annotation) accepts any literal.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from bayestribo.reports._errors import ReportError

__all__ = [
    "ParameterError",
    "ParameterSpec",
    "check_value",
    "check_values",
    "parameter_specs",
    "type_text",
]


class ParameterError(ReportError):
    """A report parameter is unknown, malformed or of the wrong type."""


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a notebook.

    Attributes
    ----------
    name : str
    default : object
        The literal default of the parameters cell.
    annotation : ast.expr or None
        The type annotation; None for a plain assignment (any literal).
    comment : str
        The line's comment (what the parameter means, with its unit).
    """

    name: str
    default: Any
    annotation: ast.expr | None
    comment: str = ""

    @property
    def type(self) -> str:
        """The type as written in the cell (``"any literal"`` without annotation)."""
        return "any literal" if self.annotation is None else type_text(self.annotation)


def type_text(annotation: ast.expr) -> str:
    """The annotation as source text (``"list[float] | None"``)."""
    return ast.unparse(annotation)


def parameter_specs(source: str) -> dict[str, ParameterSpec]:
    """Name, type, default and comment of every line of a parameters cell.

    Raises
    ------
    ParameterError
        If the cell holds anything but (annotated) assignments of literals to names,
        an annotation is not a type understood here, or a default is not of its type.
    """
    try:
        tree = ast.parse(source)
    except SyntaxError as exc:
        raise ParameterError(f"parameters cell: not valid Python ({exc.msg})") from None
    lines = source.splitlines()
    out: dict[str, ParameterSpec] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            target, annotation, value = node.targets[0], None, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            target, annotation, value = node.target, node.annotation, node.value
        else:
            raise ParameterError("parameters cell: expected plain assignments only")
        if not isinstance(target, ast.Name):
            raise ParameterError("parameters cell: expected assignments to plain names")
        try:
            default = ast.literal_eval(value)
        except ValueError:
            raise ParameterError(
                f"parameter {target.id!r}: the default is not a literal (number, string, "
                "list, dict, None...)"
            ) from None
        line = lines[node.lineno - 1]
        comment = line.split("#", 1)[1].strip() if "#" in line[node.end_col_offset or 0 :] else ""
        spec = ParameterSpec(target.id, default, annotation, comment)
        if annotation is not None:
            _check(annotation, default, target.id)  # the cell's own default must fit
        out[target.id] = spec
    return out


_SCALARS: dict[str, tuple[type, ...]] = {
    "int": (int,),
    "float": (int, float),
    "str": (str,),
    "bool": (bool,),
}


def _matches(annotation: ast.expr, value: Any, name: str) -> bool:
    if isinstance(annotation, ast.Constant) and annotation.value is None:
        return value is None
    if isinstance(annotation, ast.BinOp) and isinstance(annotation.op, ast.BitOr):
        return _matches(annotation.left, value, name) or _matches(annotation.right, value, name)
    if isinstance(annotation, ast.Name):
        if annotation.id == "Any":
            return True
        if annotation.id in _SCALARS:
            if isinstance(value, bool) and annotation.id != "bool":
                return False  # True is an int to Python, never a count to a reader
            return isinstance(value, _SCALARS[annotation.id])
        if annotation.id in ("list", "dict", "tuple"):
            return isinstance(value, {"list": list, "dict": dict, "tuple": tuple}[annotation.id])
    if isinstance(annotation, ast.Subscript) and isinstance(annotation.value, ast.Name):
        outer = annotation.value.id
        args = (
            annotation.slice.elts if isinstance(annotation.slice, ast.Tuple) else [annotation.slice]
        )
        if outer == "list" and len(args) == 1:
            return isinstance(value, list) and all(_matches(args[0], v, name) for v in value)
        if outer == "dict" and len(args) == 2:
            return isinstance(value, dict) and all(
                _matches(args[0], k, name) and _matches(args[1], v, name) for k, v in value.items()
            )
    raise ParameterError(
        f"parameter {name!r}: the annotation {type_text(annotation)!r} is not a type the "
        "reports understand (int, float, str, bool, None, Any, list[...], dict[...], A | B)"
    )


def _check(annotation: ast.expr, value: Any, name: str) -> None:
    if not _matches(annotation, value, name):
        raise ParameterError(
            f"parameter {name!r}: expected {type_text(annotation)}, got {value!r} "
            f"({type(value).__name__})"
        )


def check_value(spec: ParameterSpec, value: Any) -> None:
    """Check a value against a parameter's type.

    Raises
    ------
    ParameterError
        Naming the parameter, the expected type and the value given.
    """
    if spec.annotation is not None:
        _check(spec.annotation, value, spec.name)


def check_values(specs: Mapping[str, ParameterSpec], values: Mapping[str, Any]) -> None:
    """Check that every name is a parameter and every value has the parameter's type.

    Raises
    ------
    ParameterError
        For an unknown name (the known ones are listed) or a value of the wrong type.
    """
    unknown = sorted(set(values) - set(specs))
    if unknown:
        raise ParameterError(
            f"parameters {unknown} are not parameters of this notebook; it has {sorted(specs)}"
        )
    for key, value in values.items():
        check_value(specs[key], value)
