"""Delimited text: the canonical CSV, any column layout, and instrument exports."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.instruments import PREAMBLE_LINES, detect_export
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.run import COLUMNS, TIME
from bayestribo.io.text import decode, read_text, text_layout

__all__ = ["FORMAT"]

#: Bytes read to describe a file: enough for any instrument preamble and a header.
_HEAD_BYTES = 1 << 16


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_text(
        path,
        columns=options.columns,
        scale=options.scale,
        delimiter=options.delimiter,
        decimal=options.decimal,
        skip_rows=options.skip_rows,
        encoding=options.encoding,
    )


def _head_lines(path: Path, options: ReadOptions, count: int) -> list[str]:
    with path.open("rb") as handle:
        head = handle.read(_HEAD_BYTES)
    if len(head) == _HEAD_BYTES:
        # A multi-byte character may be cut at the end: describe whole lines only.
        head = head[: head.rfind(b"\n") + 1] or head
    return decode(head, options.encoding, str(path), say=False).splitlines()[:count]


def _is_number(text: str) -> bool:
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return True


def describe_text(path: Path, options: ReadOptions) -> dict[str, Any]:
    """The reader a text file goes to (an instrument export, a header row or none) and its
    columns, from the first lines of the file."""
    skip = options.skip_rows
    lines = _head_lines(path, options, PREAMBLE_LINES + skip)
    out: dict[str, Any] = {"reader": "delimited text", "columns": []}
    export = detect_export(lines, str(path)) if skip == 0 else None
    if export is not None:
        out["reader"] = f"{export.vendor} export"
        out["columns"] = [
            {"label": label, "unit": unit}
            for i, (label, unit) in enumerate(zip(export.labels, export.units, strict=True))
            if i not in export.ignore
        ]
        if export.implicit_time:
            out["columns"].insert(0, {"label": "time (X0, Delta_X)", "unit": "s"})
        return out
    try:
        layout = text_layout(
            lines,
            str(path),
            columns=options.columns,
            delimiter=options.delimiter,
            decimal=options.decimal,
            skip_rows=skip,
        )
    except RunFormatError:
        layout = None  # the reader names what is wrong
    body = [line for line in lines[skip:] if line.strip() and not line.startswith("#")]
    if layout is not None:
        if layout.labels:
            canonical = layout.labels[0] == COLUMNS[0] and set(layout.labels) <= set(COLUMNS)
            out["reader"] = "canonical CSV" if canonical else "delimited text with a header row"
            out["columns"] = [{"label": f, "unit": ""} for f in layout.labels]
        else:
            out["reader"] = "delimited text without a header row"
        notes = []
        if layout.preamble:
            notes.append(f"{layout.preamble} preamble line(s) skipped")
        if layout.decimal == ",":
            notes.append("decimal comma")
        if layout.stamps is not None:
            notes.append(f"time stamps in {layout.stamps!r}: seconds from the first sample")
        if TIME not in layout.names:
            note = "no time column: t = i / sample rate"
            if getattr(layout, "rate", None) is not None:
                note += f" from {layout.rate}"  # the preamble's line that states it
            notes.append(note)
        if notes:
            out["reader"] += f" ({', '.join(notes)})"
    elif body:
        first = body[0].strip()
        # the reader's own choice of delimiter: a tab, a semicolon, a comma, or blanks
        delimiter = next((d for d in ("\t", ";", ",") if d in first), None)
        fields = [f.strip().strip('"') for f in first.split(delimiter)]
        header = any(not _is_number(f) for f in fields if f)
        if header and fields[0] == COLUMNS[0] and set(fields) <= set(COLUMNS):
            out["reader"] = "canonical CSV"
            out["columns"] = [{"label": f, "unit": ""} for f in fields]
        elif header:
            out["reader"] = "delimited text with a header row"
            out["columns"] = [{"label": f, "unit": ""} for f in fields]
        else:
            out["reader"] = "delimited text without a header row"
    if skip:
        out["reader"] += f", {skip} line(s) skipped"
    return out


FORMAT = FileFormat.builtin("text", _read, describe=describe_text)
