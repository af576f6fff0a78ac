"""The bundled synthetic campaign: the paper's test programme on simulated runs.

Rigaud et al. (2010) ran three series on the same rig (m = 0.035 kg, f = 32.6 Hz):

* ``air``: no contact, ζ₀ = 0.0033 (section 2.5), three repeats;
* ``glycerol``: glycerol (0.55 % water, its measured purity) at the five loads
  0.07, 0.12, 0.31, 0.46 and 0.59 N, three repeats each; the paper reports
  ζ = 0.0236 (σ 0.0012) and μ_k = 0.0294 (σ 0.0036) over these runs (section 3.1);
* ``glycerol-water``: the six water fractions of Table 1 at two loads (0.12 and
  0.46 N, the second being the load of Fig. 11), three repeats each (section 3.2).

One series is not the paper's: ``oil``, a light oil whose runs follow a law with drag
(viscous damping, quadratic drag and Coulomb friction, ``viscous+coulomb+quadratic``
of :mod:`bayestribo.model.laws`), at the loads 0.12, 0.31 and 0.59 N, three repeats
each, so that campaigns in any law (``bayestribo campaign DIR --law auto``) have
bundled runs to show them on.

:func:`campaign_plan` draws each run's true parameters from a fixed seed:

* ζ ~ Normal(ζ̄, σ_ζ) and μ_k ~ Normal(μ̄_k, σ_μ) per run, with ζ̄ = 0.0236,
  σ_ζ = 0.0012, μ̄_k = 0.0294, σ_μ = 0.0036 for pure glycerol, as in the paper;
* in air, ζ₀ ~ Normal(0.0033, 0.0001) (the paper gives one value; a small scatter)
  and no friction;
* with water, ζ̄ = ζ₀ + (0.0236 - ζ₀)(ν/ν₀)^½, where ν is the viscosity of Eq. 43 and
  ν₀ that of the 0.55 % glycerol: ζ rises with viscosity (Fig. 10a); σ_ζ is 5 % of
  ζ̄ (as 0.0012/0.0236). μ̄_k = 0.0294 up to 6 % water and 0.0294·exp(35 (w - 0.06))
  above (about 2× at 8 % and 2.9× at 9 %: the sharp rise of Fig. 10b), with
  σ_μ = 0.0036 (μ̄_k/0.0294): larger scatter above 6 %, as the paper observes.
  The exponent ½ and the rate 35 are illustrative choices that follow the trends the
  paper describes, not values it reports;
* μ_s = 1.2 μ_k (the paper does not report μ_s);
* initial displacement 2.0 ± 0.1 mm (uniform; the magnet gives up to 2 mm),
  displacement offset uniform in ±0.3 mm, time origin uniform in [0, 100) s.
* in oil, per run ζ ~ Normal(0.006, 0.0003), μ_k ~ Normal(0.04, 0.004) and
  c₂ ~ Normal(0.35, 0.0175) kg/m (each σ 5 % of the mean, 10 % for μ_k), the same at
  every load, with μ_s = 1.2 μ_k. A vane of 4 cm² moving in an oil of density
  850 kg/m³ with a drag coefficient of 2 has c₂ = ρC_dA/2 = 0.35 kg/m. From 2 mm
  the quadratic drag makes 43-55 % of the first cycle's energy loss (43 % at 0.59 N,
  55 % at 0.12 N; (8/3)c₂Ω²A³ against 2πζkA² and 4μ_kNA), the viscous damping 30-39 %
  and the friction 7-26 %: each term is measured. These runs are simulated by
  :func:`bayestribo.synthetic.motion.integrate_law` (``solve_ivp``, not the fit's
  integrator), with the magnet's fade, from the release until the pin sticks.

Every run is recorded like the paper's vibrometer: noise at the resolution
(0.15 µm, 0.015 µm/s) and quantisation at the resolution, the ranges of section 2.3
(±5 mm, ±0.5 m/s; no run reaches them), 50 ms at rest before the
release and 100 ms after the stop. Sample rates keep the folder small: 10 kHz for
the ``glycerol`` series (about 0.4-0.85 s of motion), 2 kHz for the others (still
61 samples per period); the air runs record 3 s of their (never-ending) decay.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bayestribo._files import atomic_file
from bayestribo.io.run import Run
from bayestribo.model.laws import DEFAULT_LAW, PhysicalScale, get_law
from bayestribo.model.scaling import Rig
from bayestribo.model.viscosity import glycerol_water_viscosity
from bayestribo.synthetic.recording import simulate
from bayestribo.synthetic.setup import DissipationLaw, LawParameters, Release, Sensor

__all__ = [
    "CAMPAIGN_SEED",
    "MANIFEST_COLUMNS",
    "OIL_LAW",
    "OIL_LOADS_N",
    "OIL_POPULATION",
    "PlannedRun",
    "campaign_plan",
    "write_campaign",
]

#: Seed of the bundled campaign in ``data/``.
CAMPAIGN_SEED = 20100320

#: Paper values (sections 2.5 and 3.1).
ZETA0, ZETA_GLYCEROL, SIGMA_ZETA = 0.0033, 0.0236, 0.0012
MU_K_GLYCEROL, SIGMA_MU_K = 0.0294, 0.0036
GLYCEROL_WATER_FRACTION = 0.0055
LOADS_N = (0.07, 0.12, 0.31, 0.46, 0.59)
WATER_FRACTIONS = (0.0055, 0.023, 0.03, 0.06, 0.08, 0.09)
WATER_LOADS_N = (0.12, 0.46)
REPEATS = 3
MASS_KG, FREQUENCY_HZ = 0.035, 32.6
#: Vibrometer ranges of the paper (section 2.3): 10 mm and 1 m/s peak to peak.
DISPLACEMENT_RANGE_M, VELOCITY_RANGE_M_PER_S = 5e-3, 0.5
#: The oil series: its law (registry names), loads, and per-run means and σ (module notes).
OIL_LAW = "viscous+coulomb+quadratic"
OIL_LOADS_N = (0.12, 0.31, 0.59)
#: Each quantity a campaign compares (:mod:`bayestribo.campaign.quantities`: ζ, μ_k,
#: c₂ [kg/m]) by name: the (mean, σ) of its per-run draws, the same at every load.
OIL_POPULATION = {"zeta": (0.006, 0.0003), "mu_k": (0.04, 0.004), "c2_SI": (0.35, 0.0175)}
STATIC_RATIO = 1.2

#: The columns of the paper's law, every run's.
_PAPER_COLUMNS = (
    "run_id",
    "file",
    "series",
    "lubricant",
    "water_mass_fraction",
    "kinematic_viscosity_mm2_per_s",
    "load_N",
    "repeat",
    "zeta",
    "mu_k",
    "mu_s",
    "initial_displacement_m",
    "offset_m",
    "time_origin_s",
    "release_time_s",
    "motion_duration_s",
    "sample_rate_Hz",
    "n_samples",
    "noise_seed",
)


def _law_columns(law_name: str) -> tuple[str, ...]:
    """The true values a sidecar of ``law_name`` states that are not columns already:
    its parameters and its physical quantities (:meth:`Law.physical
    <bayestribo.model.laws.Law.physical>`), by their registry names."""
    law = get_law(law_name)
    ones = {name: np.ones(1) for name in law.parameter_names}
    physical = law.physical(ones, 1.0, PhysicalScale(1.0, 1.0, "m", 1.0, 1.0, 1.0))
    names = [*law.parameter_names, *physical]
    return tuple(n for n in dict.fromkeys(names) if n not in _PAPER_COLUMNS)


#: Columns of ``manifest.csv``: the paper's law's (ζ, μ_k, μ_s of every run), then the
#: law each run follows and the further true values of the oil series' law (μ_s/μ_k,
#: γ = c₂ℓ/m, c = 2ζmΩ [N s/m], x_c = μ_k N/k [m], c₂ [kg/m]), empty where a run's
#: sidecar does not state them.
MANIFEST_COLUMNS = (*_PAPER_COLUMNS, "law", *_law_columns(OIL_LAW))


@dataclass(frozen=True)
class PlannedRun:
    """One run of the campaign: its identity and what :func:`simulate` is given."""

    run_id: str
    series: str
    law: DissipationLaw | LawParameters
    rig: Rig
    release: Release
    sensor: Sensor
    seed: int
    metadata: Mapping[str, Any] = field(default_factory=dict)
    #: Its folder in the campaign (``runs``, or a series' own sub-folder of it).
    folder: str = "runs"

    @property
    def file(self) -> str:
        """The run's file in the campaign folder: ``<folder>/<run_id>.csv``."""
        return f"{self.folder}/{self.run_id}.csv"

    def simulate(self) -> Run:
        """Simulate the run (deterministic: the noise seed is part of the plan)."""
        return simulate(
            self.law,
            rig=self.rig,
            release=self.release,
            sensor=self.sensor,
            seed=self.seed,
            metadata=self.metadata,
        )


def _zeta_mean(water: float) -> float:
    nu_ratio = float(glycerol_water_viscosity(water) / glycerol_water_viscosity(0.0055))
    return ZETA0 + (ZETA_GLYCEROL - ZETA0) * math.sqrt(nu_ratio)


def _mu_k_mean(water: float) -> float:
    return MU_K_GLYCEROL * (math.exp(35.0 * (water - 0.06)) if water > 0.06 else 1.0)


def campaign_plan(seed: int = CAMPAIGN_SEED) -> list[PlannedRun]:
    """The runs of the campaign with their true parameters, drawn from ``seed``.

    Parameters
    ----------
    seed : int
        Seed of the parameter draws and of each run's noise seed.

    Returns
    -------
    list of PlannedRun
        Air (3), glycerol (15), glycerol-water (36) and oil (9) runs, in this order
        (a series added later draws after the others, which keep their values).
    """
    rng = np.random.default_rng(seed)
    noise_seeds = np.random.SeedSequence(seed).generate_state(200, dtype=np.uint32)
    plan: list[PlannedRun] = []

    def add(
        run_id: str,
        series: str,
        law: DissipationLaw | LawParameters,
        load_N: float,
        sample_rate_Hz: float,
        metadata: Mapping[str, Any],
        motion_duration_s: float | None = None,
        rest_after_s: float = 0.1,
        folder: str = "runs",
    ) -> None:
        index = len(plan)
        x0 = round(2.0e-3 + rng.uniform(-1e-4, 1e-4), 6)
        offset = round(rng.uniform(-3e-4, 3e-4), 6)
        t0 = round(rng.uniform(0.0, 100.0), 3)
        release = Release(
            initial_displacement_m=x0,
            rest_before_s=0.05,
            motion_duration_s=motion_duration_s,
            rest_after_s=rest_after_s,
            offset_m=offset,
            time_origin_s=t0,
        )
        sensor = Sensor(
            sample_rate_Hz=sample_rate_Hz,
            quantise=True,
            displacement_range_m=DISPLACEMENT_RANGE_M,
            velocity_range_m_per_s=VELOCITY_RANGE_M_PER_S,
        )
        rig = Rig(natural_frequency_Hz=FREQUENCY_HZ, mass_kg=MASS_KG, load_N=load_N)
        meta = {**metadata, "run_id": run_id, "series": series, "temperature_C": 20.0}
        plan.append(
            PlannedRun(
                run_id, series, law, rig, release, sensor, int(noise_seeds[index]), meta, folder
            )
        )

    for r in range(1, REPEATS + 1):
        zeta = float(rng.normal(ZETA0, 1e-4))
        add(
            f"air-r{r}",
            "air",
            DissipationLaw(zeta=zeta, mu_k=0.0),
            load_N=0.0,
            sample_rate_Hz=2000.0,
            motion_duration_s=3.0,
            rest_after_s=0.0,
            metadata={"lubricant": "none", "repeat": r},
        )
    for load in LOADS_N:
        for r in range(1, REPEATS + 1):
            zeta = float(rng.normal(ZETA_GLYCEROL, SIGMA_ZETA))
            mu_k = float(rng.normal(MU_K_GLYCEROL, SIGMA_MU_K))
            add(
                f"glycerol-N{load:.2f}-r{r}",
                "glycerol",
                DissipationLaw(zeta=zeta, mu_k=mu_k, mu_s=1.2 * mu_k),
                load_N=load,
                sample_rate_Hz=10_000.0,
                metadata={
                    "lubricant": "glycerol",
                    "water_mass_fraction": GLYCEROL_WATER_FRACTION,
                    "repeat": r,
                },
            )
    for water in WATER_FRACTIONS:
        zeta_mean, mu_mean = _zeta_mean(water), _mu_k_mean(water)
        for load in WATER_LOADS_N:
            for r in range(1, REPEATS + 1):
                zeta = float(rng.normal(zeta_mean, SIGMA_ZETA * zeta_mean / ZETA_GLYCEROL))
                mu_k = float(rng.normal(mu_mean, SIGMA_MU_K * mu_mean / MU_K_GLYCEROL))
                add(
                    f"water{100 * water:.2f}pc-N{load:.2f}-r{r}",
                    "glycerol-water",
                    DissipationLaw(zeta=zeta, mu_k=mu_k, mu_s=1.2 * mu_k),
                    load_N=load,
                    sample_rate_Hz=2000.0,
                    metadata={
                        "lubricant": "glycerol-water",
                        "water_mass_fraction": water,
                        "repeat": r,
                    },
                )
    for load in OIL_LOADS_N:
        length_scale = load / (MASS_KG * (2.0 * math.pi * FREQUENCY_HZ) ** 2)  # ℓ = N/k
        for r in range(1, REPEATS + 1):
            drawn = {q: float(rng.normal(*ms)) for q, ms in OIL_POPULATION.items()}
            values = {
                "zeta": drawn["zeta"],
                "mu_k": drawn["mu_k"],
                "mu_s_ratio": STATIC_RATIO,
                "c2": drawn["c2_SI"] * length_scale / MASS_KG,  # γ = c₂ℓ/m
            }
            add(
                f"oil-N{load:.2f}-r{r}",
                "oil",
                LawParameters(OIL_LAW, values),
                load_N=load,
                sample_rate_Hz=2000.0,
                metadata={"lubricant": "oil", "repeat": r},
                # a folder of its own: `bayestribo campaign runs/oil --law auto`
                folder="runs/oil",
            )
    return plan


def _true_values(run: Run) -> dict[str, Any]:
    """The law a simulated run follows and its true values by name, as its sidecar
    states them: ζ, μ_k and μ_s of the paper's law, or a registered law's parameters,
    its physical quantities and μ_s = (μ_s/μ_k) μ_k."""
    truth = run.metadata["simulation"]
    if "law" not in truth:  # DissipationLaw: viscous damping and Coulomb friction
        law = get_law(DEFAULT_LAW)
        if not run.metadata["load_N"]:  # without contact the friction terms are dropped
            law = get_law([t for t in law.terms if t.kind == "drag"])
        return {"law": law.name, **{k: truth[k] for k in ("zeta", "mu_k", "mu_s")}}
    values: dict[str, Any] = {"law": truth["law"]}
    for part in ("parameters", "physical"):
        values.update({name: entry["value"] for name, entry in truth[part].items()})
    if "mu_k" in values:
        values["mu_s"] = values.get("mu_s_ratio", 1.0) * values["mu_k"]
    return values


def _manifest_row(planned: PlannedRun, run: Run, file: str) -> dict[str, Any]:
    meta, truth = run.metadata, run.metadata["simulation"]
    water = meta.get("water_mass_fraction")
    values = _true_values(run)
    row = {
        "run_id": planned.run_id,
        "file": file,
        "series": planned.series,
        "lubricant": meta.get("lubricant"),
        "water_mass_fraction": "" if water is None else water,
        "kinematic_viscosity_mm2_per_s": (
            "" if water is None else repr(float(glycerol_water_viscosity(water)))
        ),
        "load_N": meta["load_N"],
        "repeat": meta["repeat"],
        "zeta": values.get("zeta", ""),
        "mu_k": values.get("mu_k", ""),
        "mu_s": values.get("mu_s", ""),
        "initial_displacement_m": truth["initial_displacement_m"],
        "offset_m": truth["offset_m"],
        "time_origin_s": float(run.time[0]),
        "release_time_s": truth["release_time_s"],
        "motion_duration_s": truth["motion_duration_s"],
        "sample_rate_Hz": meta["sample_rate_Hz"],
        "n_samples": run.n_samples,
        "noise_seed": truth["seed"],
    }
    unknown = set(values) - set(MANIFEST_COLUMNS)
    if unknown:  # a series of another law needs its columns in MANIFEST_COLUMNS
        raise ValueError(
            f"run {planned.run_id}: true values {sorted(unknown)} have no manifest column"
        )
    row.update({name: values.get(name, "") for name in MANIFEST_COLUMNS if name not in row})
    return row


def write_campaign(directory: str | Path, seed: int = CAMPAIGN_SEED) -> Path:
    """Simulate the whole campaign into ``directory``: ``runs/*.csv`` and ``runs/oil/*.csv``
    (+ sidecars), manifest.

    Parameters
    ----------
    directory : str or Path
        Output folder (created if needed). Existing run files of the same names are
        overwritten; other files are left alone.
    seed : int
        Campaign seed; the default regenerates the bundled ``data/`` exactly.

    Returns
    -------
    Path
        The manifest, ``directory/manifest.csv``, listing every run with its true
        parameters (columns :data:`MANIFEST_COLUMNS`).
    """
    from bayestribo.io import write_run

    directory = Path(directory)
    rows = []
    for planned in campaign_plan(seed):
        run = planned.simulate()
        (directory / planned.folder).mkdir(parents=True, exist_ok=True)
        write_run(run, directory / planned.file)
        rows.append(_manifest_row(planned, run, planned.file))
    manifest = directory / "manifest.csv"
    with atomic_file(manifest) as fh:
        writer = csv.DictWriter(fh, fieldnames=MANIFEST_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return manifest
