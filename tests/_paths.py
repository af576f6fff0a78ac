"""Where the tests find data: the bundled runs and the real recordings made by others.

One definition for every test module. The real recordings live outside the
repository, in ``../shared/external-data`` beside the checkout, and are read from
there, never copied. Fixtures that skip or fail on their absence are in
``conftest.py``.
"""

from __future__ import annotations

from pathlib import Path

#: The repository root.
REPO = Path(__file__).resolve().parents[1]
#: The bundled simulated campaign (``data/``) and its runs.
DATA = REPO / "data"
RUNS = DATA / "runs"
#: Real recordings made by others, outside the repository.
EXTERNAL = REPO.parent / "shared" / "external-data"
#: The AppStat2020 harmonic-oscillator recordings (HarmOsc1-3.txt).
APPSTAT = EXTERNAL / "appstat2020-harmonic-oscillator"
#: The spring, mass and disc in air recordings (semicolon text, 100 Hz).
SPRING_DISC = EXTERNAL / "smorzamento-spring-disc"
