"""The World: PD pull independent of iterations, smooth switching, ground, determinism,
and the add_body checks."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from engine import native
from engine.physics import World
from tests.engine.physics.humanoid import GUARD, MASSES, J, add_humanoid

DT = 1 / 60


def _oscillation(iterations: int, solver: str, stiffness_hz: float = 2.0, zeta: float = 0.1):
    """Humanoid without gravity pulled 5 cm forward by a lightly damped PD: the frequency (Hz)
    of the centre of mass and of the right fist oscillating about the target, from the times
    of their upward zero crossings."""
    w = World(gravity=(0, 0, 0), ground_y=-100.0, damping=0.0, iterations=iterations, solver=solver)
    b = add_humanoid(w)
    w.set_targets(b, GUARD + (0.0, 0.0, 0.05), stiffness_hz, damping_ratio=zeta)
    com, fist = [], []
    for _ in range(240):
        w.step(DT)
        x = w.x[w.bodies[b].slice]
        com.append(MASSES @ x[:, 2] / MASSES.sum() - (MASSES @ GUARD[:, 2] / MASSES.sum() + 0.05))
        fist.append(x[J["fist_r"], 2] - (GUARD[J["fist_r"], 2] + 0.05))
    return _frequency(np.array(com)), _frequency(np.array(fist)), np.array(com)


def _frequency(e: np.ndarray) -> float:
    i = np.flatnonzero((e[:-1] < 0) & (e[1:] >= 0))
    t = (i + -e[i] / (e[i + 1] - e[i])) * DT  # interpolated crossing times
    return (len(t) - 1) / (t[-1] - t[0])


@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_pd_stiffness_is_the_same_with_2_and_10_iterations(solver):
    f2_com, f2_fist, e2 = _oscillation(2, solver)
    f10_com, f10_fist, e10 = _oscillation(10, solver)
    assert f2_com == pytest.approx(f10_com, rel=0.05)
    assert f2_fist == pytest.approx(f10_fist, rel=0.05)
    # and the amplitude decays alike (same damping), not just the same period
    assert np.abs(e2[120:]).max() == pytest.approx(np.abs(e10[120:]).max(), rel=0.05)
    # the measured frequency is the one asked for (damped: f sqrt(1 - zeta^2)); the implicit
    # integration lowers it by atan(w dt)/(w dt), 3 % at 2 Hz and 60 Hz
    assert f2_com == pytest.approx(2.0 * np.sqrt(1 - 0.1**2), rel=0.06)


def test_critically_damped_step_response_does_not_overshoot():
    w = World(gravity=(0, 0, 0), ground_y=-100.0, damping=0.0)
    b = w.add_body(np.zeros((1, 3)), [1.0], np.zeros((0, 2)), np.zeros((0, 2)), [], [])
    w.set_targets(b, [[0.1, 0.0, 0.0]], 3.0, damping_ratio=1.0)
    xs = []
    for _ in range(120):
        w.step(DT)
        xs.append(w.x[0, 0])
    xs = np.array(xs)
    assert np.all(np.diff(xs) >= -1e-12) and xs.max() <= 0.1 + 1e-9
    assert xs[-1] == pytest.approx(0.1, abs=1e-3)


def test_very_stiff_pull_is_stable():
    w = World(gravity=(0, 0, 0), ground_y=-100.0)
    b = add_humanoid(w)
    w.set_targets(b, GUARD + 0.02, 200.0)  # w dt = 21: explicit integration would explode
    for _ in range(60):
        w.step(DT)
    assert np.abs(w.x - (GUARD + 0.02)).max() < 0.01


def test_discontinuous_switch_is_smooth():
    """A 30 cm jump of the reference (plus a punch pose) moves the body with bounded
    acceleration and speed; without the clamps the same jump is much harsher."""
    def run(**kw):
        w = World(**kw)
        b = add_humanoid(w)
        w.set_targets(b, GUARD, 8.0)
        for _ in range(60):
            w.step(DT)
        punch = GUARD.copy()
        punch[J["fist_r"]] += (0.0, 0.1, 0.45)
        punch[J["elbow_r"]] += (0.0, 0.15, 0.2)
        w.set_targets(b, punch + (0.0, 0.0, 0.3), 8.0)
        v_prev = w.velocity(DT).copy()
        peak_com_acc = peak_speed = 0.0
        for _ in range(60):
            w.step(DT)
            v = w.velocity(DT)
            peak_com_acc = max(peak_com_acc, np.linalg.norm(MASSES @ (v - v_prev)) / MASSES.sum() / DT)
            peak_speed = max(peak_speed, np.linalg.norm(v, axis=1).max())
            v_prev = v.copy()
        return peak_com_acc, peak_speed, w.x.copy()

    acc, speed, x = run()
    acc_free, _, _ = run(max_accel=np.inf, max_speed=np.inf)
    w = World()
    assert acc <= w.max_accel + 9.81 + 1.0
    assert speed <= w.max_speed + 1e-9
    assert acc_free > 1.1 * acc
    # and it got there: the body moved its 30 cm, the fist reached out (as far as the arm goes)
    com_z = MASSES @ x[:, 2] / MASSES.sum() - MASSES @ GUARD[:, 2] / MASSES.sum()
    assert com_z == pytest.approx(0.3 + MASSES[J["fist_r"]] * 0.45 / MASSES.sum(), abs=0.03)
    assert x[J["fist_r"], 2] - GUARD[J["fist_r"], 2] > 0.55


def test_ground_plane_holds_a_falling_body():
    w = World(ground_y=0.25)
    b = add_humanoid(w)
    w.set_positions(b, GUARD + (0.0, 1.0, 0.0))
    w.clear_targets(b)
    lowest = []
    for _ in range(180):
        w.step(DT)
        lowest.append(w.x[:, 1].min())
    assert min(lowest) >= 0.25 - 1e-12
    assert lowest[-1] == pytest.approx(0.25, abs=1e-6)  # it lies on the ground
    assert np.abs(w.velocity(DT)[:, 1]).max() < 0.5


def test_ground_friction_slows_sliding():
    def slide(friction):
        w = World(ground_friction=friction)
        b = w.add_body([[0.0, 0.0, 0.0]], [1.0], np.zeros((0, 2)), np.zeros((0, 2)), [], [])
        w.x_prev[0] = (-2.0 * DT, 0.0, 0.0)  # moving at 2 m/s along +x on the ground
        for _ in range(30):
            w.step(DT)
        return w.x[b, 0]
    assert slide(0.5) < 0.5 * slide(0.0)


def _scenario(world: World, perturb: float = 0.0) -> str:
    a = add_humanoid(world, 0.0, -0.7, 0.0)
    b = add_humanoid(world, 0.0, 0.7, np.pi)
    from tests.engine.physics.humanoid import place
    for i in range(90):
        z = -0.7 + i * 0.01
        world.set_targets(a, place(GUARD, 0.0, z + perturb, 0.0), 5.0)
        world.set_targets(b, place(GUARD, 0.0, -z, np.pi), 5.0)
        world.step(DT)
    return world.state_hash()


def test_same_inputs_give_the_same_state_hash():
    h1 = _scenario(World())
    h2 = _scenario(World())
    assert h1 == h2
    assert _scenario(World(), perturb=1e-9) != h1


def test_add_body_rejects_bad_input():
    w = World()
    ok = dict(positions=np.zeros((2, 3)) + [[0, 0, 0], [0, 1, 0]], masses=[1.0, 1.0], sticks=[[0, 1]],
              capsules=[[0, 1]], radii=[0.1], capsule_tags=["x"])
    with pytest.raises(ValueError):
        w.add_body(**{**ok, "masses": [1.0, 0.0]})
    with pytest.raises(ValueError):
        w.add_body(**{**ok, "sticks": [[0, 2]]})
    with pytest.raises(ValueError):
        w.add_body(**{**ok, "capsule_tags": []})
    with pytest.raises(ValueError):
        w.add_body(**{**ok, "limits": ([[0, 1]], [[1.0, 0.5]])})
    with pytest.raises(ValueError):
        w.step(0.0)
    bid = w.add_body(**ok)
    assert w.bodies[bid].slice == slice(0, 2) and w.x.shape == (2, 3)
    with pytest.raises(ValueError):
        w.set_targets(bid, np.zeros((3, 3)), 5.0)


def test_bodies_are_slices_of_one_array():
    w = World()
    a = add_humanoid(w, 0.0, -1.0, 0.0)
    b = add_humanoid(w, 0.0, 1.0, np.pi)
    assert w.x.shape == (34, 3) and w.x_prev.shape == (34, 3)
    assert w.bodies[a].slice == slice(0, 17) and w.bodies[b].slice == slice(17, 34)
    np.testing.assert_allclose(w.x[w.bodies[a].slice], GUARD + (0.0, 0.0, -1.0))


def test_joint_limit_keeps_an_elbow_from_folding_shut():
    """The fist pulled onto its own shoulder: the limit (min 35 % of the arm) holds it off."""
    from tests.engine.physics.humanoid import limit_ranges

    w = World(gravity=(0, 0, 0), ground_y=-100.0)
    b = add_humanoid(w)
    folded = GUARD.copy()
    folded[J["fist_r"]] = GUARD[J["shoulder_r"]] + (0.0, 0.0, 0.01)
    w.set_targets(b, folded, 8.0)
    for _ in range(60):
        w.step(DT)
    x = w.x[w.bodies[b].slice]
    d = np.linalg.norm(x[J["fist_r"]] - x[J["shoulder_r"]])
    assert d >= limit_ranges()[1, 0] - 0.03  # a 4-iteration Jacobi against an 8 Hz pull
    # and without the limit the same pull does fold it
    w2 = World(gravity=(0, 0, 0), ground_y=-100.0)
    b2 = add_humanoid(w2, limits=False)
    w2.set_targets(b2, folded, 8.0)
    for _ in range(60):
        w2.step(DT)
    x2 = w2.x[w2.bodies[b2].slice]
    assert np.linalg.norm(x2[J["fist_r"]] - x2[J["shoulder_r"]]) < d - 0.05


def test_target_velocities_reduce_the_lag_behind_a_moving_target():
    def lag(with_velocity: bool) -> float:
        w = World(gravity=(0, 0, 0), ground_y=-100.0, damping=0.0)
        b = w.add_body(np.zeros((1, 3)), [1.0], np.zeros((0, 2)), np.zeros((0, 2)), [], [])
        for i in range(120):
            t = np.array([[1.0 * (i + 1) * DT, 0.0, 0.0]])  # 1 m/s along x
            w.set_targets(b, t, 4.0, velocities=np.array([[1.0, 0.0, 0.0]]) if with_velocity else None)
            w.step(DT)
        return float(t[0, 0] - w.x[0, 0])
    plain, fed = lag(False), lag(True)
    assert plain > 0.05  # 2 zeta / w = 80 ms behind at 1 m/s
    assert abs(fed) < 0.2 * plain


def test_set_targets_rejects_non_finite():
    w = World()
    b = add_humanoid(w)
    bad = GUARD.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError):
        w.set_targets(b, bad, 5.0)


def test_three_bodies_collide_pairwise():
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
    for x in (-0.3, 0.0, 0.3):
        w.add_body([[x, 1.0, 0.0]], [1.0], np.zeros((0, 2)), [[0, 0]], [0.2], [f"ball{x}"])
    assert len(w.pairs) == 3  # (0,1), (0,2), (1,2)
    contacts = w.step(DT)
    assert {(c.body_a, c.body_b) for c in contacts} == {(0, 1), (1, 2)}
    for _ in range(30):
        w.step(DT)
    gaps = np.diff(np.sort(w.x[:, 0]))
    assert np.all(gaps >= 0.4 - 0.002)


_HASH_RUN = """
import json
import numpy as np
from engine import native
from engine.physics import World
from tests.engine.physics.humanoid import GUARD, add_humanoid, place
w = World()
a = add_humanoid(w, 0.0, -1.0, 0.0)
b = add_humanoid(w, 0.05, 1.0, np.pi)
for i in range(150):
    z = min(-1.0 + 0.6 * i / 60, -0.05)
    w.set_targets(a, place(GUARD, 0.0, z, 0.0), 5.0)
    w.set_targets(b, place(GUARD, 0.05, -z, np.pi), 5.0)
    w.step(1 / 60)
print(json.dumps({"hash": w.state_hash(), "kernels": native.status()}))
"""
PHYSICS_KERNELS = ("contacts", "stick_project")


def _hash_run(extra: dict, cache: Path) -> dict:
    """The scene above in a fresh interpreter -> {"hash", "kernels": native.status()}; the
    kernels built into (or read from) `cache`, never the user's cache."""
    import json
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[3]
    env = {k: v for k, v in os.environ.items() if k not in (native.NO_NATIVE_ENV, native.NO_JIT_ENV, "CC")}
    env.update({native.CACHE_ENV: str(cache), "TMPDIR": str(cache.parent), **extra})
    out = subprocess.run([sys.executable, "-c", _HASH_RUN], cwd=root, env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    return json.loads(out.stdout)


needs_cc = pytest.mark.skipif(os.name != "posix" or native.compiler() is None,
                              reason="no C compiler: the kernels cannot be built here")


@needs_cc
def test_state_hash_does_not_depend_on_the_cpu_kernels(tmp_path):
    """The step uses no BLAS (whose kernels OpenBLAS picks per CPU and which round
    differently), so forcing another kernel set, or numpy without its AVX paths, must give
    the same bits: two bodies walking into each other, contacts included. The same with and
    without the C kernels (engine/native.py: QUICKJAB_NO_NATIVE=1 runs numpy); the native
    runs really ran them."""
    runs = [_hash_run(extra, tmp_path / "cache") for extra in (
        {}, {"OPENBLAS_CORETYPE": "Prescott", "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4"},
        {native.NO_NATIVE_ENV: "1"})]
    for run in runs[:2]:
        assert all(run["kernels"][k].startswith("native") for k in PHYSICS_KERNELS), run["kernels"]
    assert all(runs[2]["kernels"][k].startswith("numpy") for k in PHYSICS_KERNELS)
    assert len({r["hash"] for r in runs}) == 1


def _plant(cache: Path, what: str) -> None:
    """Break the cached physics kernels: garbage, or a library lacking their symbols."""
    from engine.physics import collision, constraints

    cache.mkdir(parents=True, exist_ok=True)
    if what == "garbage":
        data = b"\x7fELF but not really"
    else:
        other = native.load_library("unrelated", "int unrelated(void) { return 1; }\n", ("unrelated",))
        assert other is not None
        data = native.library_path("unrelated", "int unrelated(void) { return 1; }\n").read_bytes()
    for stem, source in (("contacts", collision.KERNEL_SOURCE), ("stick_project", constraints.PROJECT_SOURCE)):
        native.library_path(stem, source, directory=cache).write_bytes(data)


@needs_cc
@pytest.mark.parametrize("case", ["corrupt", "missing_symbol", "missing_symbol_no_cc", "failing_cc",
                                  "unwritable_cache"])
def test_broken_kernels_fall_back_cleanly_with_the_same_state(case, tmp_path, monkeypatch):
    """Each breakage ends in the C kernels (rebuilt) or numpy, never a traceback, and the world
    steps to the numpy run's bits either way."""
    monkeypatch.setenv(native.CACHE_ENV, str(tmp_path / "planted"))
    reference = _hash_run({native.NO_NATIVE_ENV: "1"}, tmp_path / "ref")["hash"]
    cache, extra, expect = tmp_path / "cache", {}, "native"
    if case == "corrupt":
        _plant(cache, "garbage")
    elif case.startswith("missing_symbol"):
        _plant(cache, "unrelated")
        if case.endswith("no_cc"):
            extra, expect = {"CC": "/bin/false"}, "numpy"
    elif case == "failing_cc":
        extra, expect = {"CC": "/bin/false"}, "numpy"
    else:
        (tmp_path / "file").write_text("")
        cache = tmp_path / "file" / "cache"  # cannot be created, even by root: the temp dir is used
        extra = {"TMPDIR": str(tmp_path)}
    run = _hash_run(extra, cache)
    assert all(run["kernels"][k].startswith(expect) for k in PHYSICS_KERNELS), run["kernels"]
    assert run["hash"] == reference
    if case == "failing_cc":  # remembered: the next start runs no compiler
        again = _hash_run(extra, cache)
        assert all("remembered" in again["kernels"][k] for k in PHYSICS_KERNELS), again["kernels"]
    if case == "unwritable_cache":
        assert any((tmp_path / f"quickjab-{os.getuid()}").glob("contacts-*.so"))


def test_the_world_loads_its_kernels_when_built_not_in_a_step(monkeypatch):
    """The contact kernel's first build (a compiler run) happens when the World is built, as
    IncrementalDTW does at construction, never inside the first 60 Hz step with a contact."""
    from engine.physics import collision, constraints

    monkeypatch.setattr(collision, "_kernels", [])
    monkeypatch.setattr(constraints, "_kernel", [])
    World()
    assert len(collision._kernels) == 1 and len(constraints._kernel) == 1


def test_damping_is_per_second_not_per_step():
    def speed_after_1s(dt: float) -> float:
        w = World(gravity=(0, 0, 0), ground_y=-100.0, damping=0.05)
        w.add_body([[0.0, 0.0, 0.0]], [1.0], np.zeros((0, 2)), np.zeros((0, 2)), [], [])
        w.x_prev[0] = (-2.0 * dt, 0.0, 0.0)  # 2 m/s
        for _ in range(round(1.0 / dt)):
            w.step(dt)
        return float(w.velocity(dt)[0, 0])
    assert speed_after_1s(1 / 60) == pytest.approx(2.0 * 0.95**60, rel=1e-9)
    assert speed_after_1s(1 / 120) == pytest.approx(speed_after_1s(1 / 60), rel=1e-9)


def test_changing_the_gains_takes_effect():
    """set_targets caches the gains it was last given; a change must still reach the step."""
    def run(gains):
        w = World(gravity=(0, 0, 0), ground_y=-100.0)
        b = add_humanoid(w)
        for g in gains:
            w.set_targets(b, GUARD + 0.1, *g)
            w.step(DT)
        return w.x.copy()
    per_particle = np.full(17, 8.0)
    np.testing.assert_array_equal(run([(2.0, 1.0), (8.0, 1.0)]), run([(2.0, 1.0), (per_particle, 1.0)]))
    assert not np.array_equal(run([(2.0, 1.0), (8.0, 1.0)]), run([(2.0, 1.0), (2.0, 1.0)]))
    assert not np.array_equal(run([(8.0, 1.0), (8.0, 0.3)]), run([(8.0, 1.0), (8.0, 1.0)]))
