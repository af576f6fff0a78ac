"""The benchmark measures the package of its own tree, never another installed one."""

from __future__ import annotations

from pathlib import Path

TREE = Path(__file__).resolve().parent.parent


def require_this_tree() -> str:
    """The path of the imported ``bayestribo``; exits naming the fix when it is not
    this tree's (an editable install of another worktree, or a site-packages copy,
    would be measured and labelled with this tree's commit)."""
    import bayestribo

    module = Path(bayestribo.__file__).resolve()
    if TREE not in module.parents:
        raise SystemExit(
            f"bayestribo is imported from {module}, not from this tree ({TREE}): "
            f"run with PYTHONPATH={TREE} (or pip install -e {TREE})"
        )
    return str(module)
