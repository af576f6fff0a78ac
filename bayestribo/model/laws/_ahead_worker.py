"""A worker of :mod:`bayestribo.model.laws.ahead`: compiles the laws it is sent.

Run as ``python -m bayestribo.model.laws._ahead_worker PARENT_PID`` with the law cache
in ``BAYESTRIBO_CACHE_DIR``. Reads lines ``<law name>\t<module name>`` on its standard
input, compiles each (:func:`bayestribo.model.laws.ahead.compile_law`) and answers one
line per law, ``ok <module>`` or ``failed <module> <why>``; ends at the end of its input
or with the process ``PARENT_PID``.
"""

from __future__ import annotations

import sys


def main(argv: list[str]) -> int:
    """Serve the laws read from standard input (module notes)."""
    from bayestribo._workers import die_with_parent
    from bayestribo.model.laws.ahead import compile_law

    die_with_parent(int(argv[0]))
    for line in sys.stdin:
        law, _, module = line.rstrip("\n").partition("\t")
        try:
            compile_law(law, module)
        except Exception as exc:  # the command compiles the law itself
            why = " ".join(str(exc).split())
            print(f"failed {module} {type(exc).__name__}: {why}", flush=True)
        else:
            print(f"ok {module}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
