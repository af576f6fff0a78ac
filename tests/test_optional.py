"""Optional extras: the package imports without them, and a feature that needs a
missing one says in one line what to install."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from bayestribo.errors import BayestriboError, MissingDependencyError

BLOCKED = ("pyuff", "nptdms", "serial", "nbformat", "nbclient", "nbconvert", "dask")


def test_every_module_imports_without_the_extras():
    # Block the optional packages before anything is imported (a fresh interpreter).
    code = textwrap.dedent(
        f"""
        import sys
        for name in {BLOCKED!r}:
            sys.modules[name] = None
        import pkgutil, importlib, bayestribo
        for info in pkgutil.walk_packages(bayestribo.__path__, "bayestribo."):
            if not info.name.endswith("__main__"):  # that one runs the command line
                importlib.import_module(info.name)
        from bayestribo.cli import main
        print("ok")
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


@pytest.mark.parametrize(
    ("module", "call", "extra"),
    [
        ("pyuff", lambda tmp: __import__("bayestribo").read_run(tmp / "x.uff"), "formats"),
        ("nptdms", lambda tmp: __import__("bayestribo").read_run(tmp / "x.tdms"), "formats"),
        (
            "serial",
            lambda tmp: __import__("bayestribo.acquisition.port").acquisition.port.open_port(
                "loop://"
            ),
            "acquire",
        ),
        (
            "nbformat",
            lambda tmp: __import__("bayestribo.reports.notebooks").reports.notebooks.read_notebook(
                "single_run"
            ),
            "report",
        ),
    ],
)
def test_a_missing_extra_is_one_line_naming_it(module, call, extra, monkeypatch, tmp_path):
    (tmp_path / "x.uff").write_text("not a uff file")
    (tmp_path / "x.tdms").write_bytes(b"not a tdms file")
    monkeypatch.setitem(sys.modules, module, None)
    with pytest.raises(MissingDependencyError) as caught:
        call(tmp_path)
    message = str(caught.value)
    assert f"pip install 'bayestribo[{extra}]'" in message and "\n" not in message
    assert isinstance(caught.value, BayestriboError) and isinstance(caught.value, ImportError)


def test_dask_executor_without_dask(monkeypatch):
    from bayestribo.campaign.fitting import dask_executor

    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    with pytest.raises(MissingDependencyError, match=r"bayestribo\[dask\]"):
        with dask_executor():
            pass
