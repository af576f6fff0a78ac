"""``--window T0:T1`` and ``read_run(window=...)``: the part of a record analysed."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli.main import main
from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io.files import write_run
from bayestribo.io.run import Run


@pytest.fixture
def record(tmp_path):
    t = np.arange(0.0, 10.0, 0.01)
    x = np.exp(-0.1 * t) * np.cos(2 * np.pi * 1.3 * t)
    return write_run(Run(t, x, metadata={"length_unit": "arbitrary"}), tmp_path / "r.csv"), t


def test_the_window_keeps_its_samples_and_says_so(record):
    path, t = record
    run = read_run(path, window=(2.0, 5.0))
    np.testing.assert_array_equal(run.time, t[(t >= 2.0) & (t <= 5.0)])
    assert run.metadata["window_s"] == [2.0, 5.0]
    # an open end is the record's own
    assert read_run(path, window=(2.0, np.inf)).metadata["window_s"] == [2.0, t[-1]]


@pytest.mark.parametrize(
    ("window", "error", "match"),
    [
        ((5.0, 2.0), BayestriboError, "t0 < t1"),
        ((20.0, 30.0), RunFormatError, r"holds 0 sample\(s\); the record spans 0 s to 9.99 s"),
        (("a", 2), BayestriboError, "two times"),
        # an integer beyond a float's range (a JSON sidecar may hold one)
        ((10**400, None), BayestriboError, "two times"),
    ],
)
def test_a_window_that_cannot_be_is_refused(record, window, error, match):
    with pytest.raises(error, match=match):
        read_run(record[0], window=window)


def test_the_command_line_window(record, capsys):
    path, _ = record
    assert main(["inspect", str(path), "--window", "3:"]) == 0
    assert "from t = 3 s" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["inspect", str(path), "--window", "3"])
    assert "--window-length" in capsys.readouterr().err


@pytest.mark.parametrize("text", [":5", "3:"])
def test_an_open_window_is_a_fit_specifications_json(record, text):
    # `fit --window :5` wrote the spec with -inf and stopped with a traceback
    # ("Out of range float values are not JSON compliant") before the fit's output
    import argparse
    import json

    from bayestribo.cli._common import add_reading_options, reading_options
    from bayestribo.inference.spec import FitSpec

    parser = argparse.ArgumentParser()
    add_reading_options(parser)
    options = reading_options(parser.parse_args(["--window", text]))
    spec = FitSpec(read_options=options)
    written = json.loads(spec.to_json())["read_options"]["window"]
    assert None in written  # the open end, as JSON holds it
    again = FitSpec.from_json(spec.to_json()).read_options
    assert again.window == options.window
    t0, t1 = again.window
    assert read_run(record[0], window=(t0, t1)) == read_run(record[0], options=options)
