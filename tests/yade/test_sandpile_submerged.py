"""The submerged sand pile (examples/sandpile/sandpile.py --submerged: yade_mpm.sandpile.SUBMERGED,
excess pore pressure under still water, theory.md eq. 1.9, semi-implicit at real water, no
relaxation), quick mode, α = 100, cut at 1.2 s — the second second of the 60 s rise has begun (a
full run that yields at the limit-equilibrium head takes minutes: doc/sandpile.md). It stands while
the head is at the still level, where limit equilibrium says it must."""
import json
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def submerged_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("submerged")
    env = dict(os.environ, HOME=str(out))
    done = subprocess.run(["yade-double", "-j2", "-n", "-x", os.path.join(ROOT, "examples", "sandpile", "sandpile.py"), "--quick", "--submerged",
                           "--scheme", "semi-implicit", "--inertia-scale", "100", "--duration", "1.2", "--out", str(out)],
                          capture_output=True, text=True, timeout=600, env=env, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    with open(out / "summary.json") as f:
        return json.load(f)


def test_submerged_pile_stands_at_the_still_level(submerged_run):
    """At the still level there is no seepage: elastic settlement only (γ′H²/E ≈ 1 µm; measured
    2.3 µm at 1 s), the inertia scale is not released, and Bishop's F on the run's own state is the
    dry pile's (Davis φ* = 31.9° on a 30° slope: measured 1.085) — the at-rest submerged slope
    stands by its strength, as the scene intends; deeper slides by a wider margin."""
    s = submerged_run
    assert s["stopped_unstable"] is None
    before = s["stable_before_rise"]
    assert abs(before["toe_displacement_m"]) < 1e-5 and abs(before["face_displacement_m"]) < 1e-5
    assert s["inertia_scale_release_time_s"] is None
    assert s["limit_equilibrium"]["factors"][0] > 1
    # the example also writes Bishop on slides at least three cells deep (the depth the grid resolves
    # as a band): those circles are a subset of the search, so F ≥ the skin's by construction, and
    # strictly so because a cohesionless slope at rest is most critical at its skin (1.32 against 1.09)
    lem = s["limit_equilibrium"]
    assert lem["deep_min_depth_m"] == pytest.approx(3 * s["cell_size_m"])
    assert lem["deep_factors"][0] > lem["factors"][0]
    # and at the sand's peak strength (no Davis reduction; tan 36° = 0.727 against tan 31.9° = 0.623):
    # with c = 0 Bishop's F grows with tan φ, so the same search at the peak stands higher at every frame.
    # F is nearly proportional to tan φ (not exactly: tan φ/F also enters each slice's m_α), so at rest
    # the ratio is close to 0.727/0.623 = 1.17; asserted above 1.1 (in-run: 1.62 against 1.39 at rest,
    # 1.13 against 0.97 at 41.7 s of the 60 s lidded run)
    assert all(p > d for p, d in zip(lem["deep_peak_factors"], lem["deep_factors"]) if p is not None and d is not None)
    assert lem["deep_peak_factors"][0] > 1.1 * lem["deep_factors"][0]


def test_submerged_pile_water_balance_closes(submerged_run):
    """The excess-pressure run keeps every water point's mass accounted for (stored + removed =
    initial + injected) to 1e-9."""
    assert abs(submerged_run["relative_residual"]) < 1e-9


@pytest.mark.parametrize("flags, message", [(["--crest-lid", "--lid-friction", "-0.1"], "--lid-friction must be ≥ 0"),
                                            (["--lid-friction", "0.5"], "--lid-friction 0.5 needs --crest-lid"),
                                            (["--side-wall-friction", "-1"], "--side-wall-friction must be ≥ 0"),
                                            (["--sand-from-dem", "no-such-run"], "--sand-from-dem 'no-such-run': no summary.json there"),
                                            (["--dem-strength-only"], "--dem-strength-only needs --sand-from-dem DIR"),
                                            (["--sand-from-dem", os.path.join(ROOT, "doc", "compare", "sandpile", "dem-run"), "--inertia-scale", "100"],
                                             "--inertia-scale = 100.0 is outside the valid range [1, ")])
def test_lid_friction_is_refused_before_any_work(tmp_path, flags, message):
    """A negative Coulomb coefficient has no meaning, and a lid friction without a lid would be
    silently ignored: both stop at once with the flag's name, value and what is valid; so does a
    DEM run directory that holds no summary to take the sand from, and an inertia scaling under which
    the coarse DEM grains' drag relaxation (α ρsat κ/μw ≈ 20 s at α = 100) would lag the pore pressure
    behind a 60 s head rise."""
    done = subprocess.run(["yade-double", "-n", "-x", os.path.join(ROOT, "examples", "sandpile", "sandpile.py"), "--quick", "--submerged",
                           "--scheme", "semi-implicit", "--out", str(tmp_path)] + flags,
                          capture_output=True, text=True, timeout=120, env=dict(os.environ, HOME=str(tmp_path)), stdin=subprocess.DEVNULL)
    assert done.returncode != 0
    assert message in done.stdout + done.stderr
    assert not (tmp_path / "summary.json").exists()
