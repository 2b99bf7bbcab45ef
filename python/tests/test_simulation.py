"""snh.Simulation and snh.run_scene: the stretch test stepped from Python equals tetcli's frames; a pin
motion driven from Python equals the same motion written as a scene; energy, gradient and Hessian agree
with finite differences; bad input, non-convergence and Ctrl-C."""
import math
import os
import signal

import numpy as np
import pytest

import snh
from conftest import as_obj_text, program, read_obj_vertices

SNH = snh.material("stable_neo_hookean", mu=1.0, lam=10.0)


def test_stretch_equals_tetcli(tmp_path):
    # tetcli 3 stable_neo_hookean 1.0 10.0 OUT: 25 quasi-static steps to a 3.5x stretch along y.
    import subprocess
    out = tmp_path / "tetcli"
    subprocess.run([program("SNH_TETCLI"), "3", "stable_neo_hookean", "1.0", "10.0", str(out)], check=True,
                   capture_output=True, timeout=120)
    V, C, _ = snh.box("tet4", 3)
    bottom, top = np.flatnonzero(V[:, 1] == -1.0), np.flatnonzero(V[:, 1] == 1.0)
    pinned = np.concatenate([bottom, top])
    steps, stretch = 25, 3.5

    def length(t):
        return 1.0 + (stretch - 1.0) * t / steps

    def first_guess(x, t):  # tetcli's: the rest state stretched to the new boundary
        g = x.copy()
        g[:, 1] = 0.0 + (g[:, 1] - 0.0) * length(t)
        return g

    sim = snh.Simulation(V, C, SNH, pinned, integrator="quasi_static", first_guess=first_guess,
                         solver="pcg")  # tetcli's solver, as the paper's programs
    assert sim.pinned.tolist() == pinned.tolist()
    assert read_obj_vertices(out / "000.obj") == as_obj_text(sim.positions)
    for s in range(1, steps + 1):
        targets = V[pinned].copy()
        targets[:, 1] = 0.0 + (targets[:, 1] - 0.0) * length(s)
        sim.targets = targets
        stats = sim.step(s)
        assert stats["converged"] and stats["residual"] < 1e-3
        assert stats["truncated_steps"] == 0 and stats["chord_steps"] == 0  # only mg and amg take them
        assert read_obj_vertices(out / f"{s:03d}.obj") == as_obj_text(sim.positions), f"step {s}"
    assert sim.steps == steps and sim.time == steps


def pin_scene(tmp_path):
    return {
        "mesh": {"box": {"element": "hex", "res": 2}},
        "material": {"name": "stable_neo_hookean", "mu": 1, "lambda": 10},
        "integrator": "backward_euler", "dt": 0.1, "end_time": 1, "frames": 5,
        "gravity": [0, -1, 0],
        "damping": {"mass": 0.1},
        "pins": [{"region": {"min": [-1, -1, -1], "max": [1, -1, 1]}},
                 {"region": {"min": [-1, 1, -1], "max": [1, 1, 1]},
                  "motion": [{"type": "translate", "by": [0.4, 0.2, 0], "start": 0, "end": 1}]}],
        "solver": {"tolerance": 1e-7},
        "output": {"dir": str(tmp_path / "scene"), "vtu": False},
    }


def test_python_pin_motion_equals_the_scene(tmp_path):
    scene = pin_scene(tmp_path)
    result = snh.run_scene(scene, quiet=True, report=False)
    assert result["all_converged"] and result["frames"] == 6
    V, C, _ = snh.box("hex", 2)
    bottom, top = np.flatnonzero(V[:, 1] == -1.0), np.flatnonzero(V[:, 1] == 1.0)
    pinned = np.concatenate([bottom, top])
    # The scene's substeps: frames of end_time / frames, split into ceil(frame / dt) substeps.
    frame_dt, substeps = 1.0 / 5, 2
    h = frame_dt / substeps
    sim = snh.Simulation(V, C, SNH, pinned, integrator="backward_euler", dt=h, gravity=[0, -1, 0], mass_damping=0.1,
                         tolerance=1e-7, relative_step_tolerance=1e-8)
    by = np.array([0.4, 0.2, 0.0])
    for frame in range(1, 6):
        for k in range(1, substeps + 1):
            t = (frame - 1) * frame_dt + k * h
            p = min(max((t - 0.0) / (1.0 - 0.0), 0.0), 1.0)
            sim.targets = np.concatenate([V[bottom], V[top] + p * by])
            sim.step(t)
        assert read_obj_vertices(tmp_path / "scene" / f"{frame:03d}.obj") == as_obj_text(sim.positions), f"frame {frame}"
    np.testing.assert_array_equal(result["final_positions"], sim.positions)
    assert np.abs(sim.velocities).max() > 0


def test_run_scene_file_matches_snh_run(tmp_path):
    import json
    import subprocess
    scene = pin_scene(tmp_path)
    path = tmp_path / "pins.json"
    path.write_text(json.dumps(scene))
    r = snh.run_scene(str(path), out=tmp_path / "py", quiet=True)
    assert r["report"] and os.path.exists(r["report"])
    subprocess.run([program("SNH_BIN"), "run", str(path), "--out", str(tmp_path / "cli"), "--no-report"], check=True,
                   capture_output=True, timeout=120)
    for frame in range(6):
        assert (tmp_path / "py" / f"{frame:03d}.obj").read_text() == (tmp_path / "cli" / f"{frame:03d}.obj").read_text()


def test_run_scene_keep_going(tmp_path):
    # One Newton iteration a frame (and no step retried in halves) cannot hold a falling box: every frame fails.
    scene = {"mesh": {"box": {"res": 2}}, "gravity": [0, -9.8, 0], "frames": 4, "end_time": 0.4,
             "solver": {"max_iterations": 1, "step_halvings": 0}, "pins": [{"region": {"min": [-1, 1, -1], "max": [1, 1, 1]}}]}
    r = snh.run_scene(scene, out=tmp_path / "stop", quiet=True, report=False, check=False)
    assert r["frames"] == 2 and r["unconverged_frames"] == [1]
    r = snh.run_scene(scene, out=tmp_path / "going", quiet=True, report=False, check=False, keep_going=True)
    assert r["frames"] == 5 and r["unconverged_frames"] == [1, 2, 3, 4] and not r["all_converged"]
    assert r["failure"].startswith("frame 1, ")
    with pytest.raises(RuntimeError, match="^frame 1, "):
        snh.run_scene(scene, out=tmp_path / "raises", quiet=True, report=False, keep_going=True)
    assert (tmp_path / "raises" / "004.obj").exists()


def test_run_scene_errors(tmp_path):
    scene = pin_scene(tmp_path)
    scene["dt"] = -1
    with pytest.raises(ValueError, match="^scene: dt: must be > 0, got -1$"):
        snh.run_scene(scene)
    with pytest.raises(ValueError, match=r"^scene: mesh.box.bogus: unknown key"):
        snh.run_scene({"mesh": {"box": {"bogus": 1}}})


def small_system(pinned=None, **kw):
    V, C, _ = snh.box("hex", 2)
    return V, C, snh.Simulation(V, C, SNH, pinned, **kw)


def test_energy_gradient_hessian_by_finite_differences():
    V, C, sim = small_system()
    assert sim.energy() == pytest.approx(0.0, abs=1e-12)
    rng = np.random.default_rng(4)
    x = V * [1.2, 0.9, 1.0] + 0.05 * rng.standard_normal(V.shape)
    g, H = sim.gradient(x), sim.hessian(x)
    n = 3 * len(V)
    H = H.toarray() if hasattr(H, "toarray") else H
    assert H.shape == (n, n)
    np.testing.assert_allclose(H, H.T, atol=1e-12)
    h = 1e-6
    for d in range(0, n, 5):
        e = np.zeros(n)
        e[d] = h
        e = e.reshape(-1, 3)
        fd = (sim.energy(x + e) - sim.energy(x - e)) / (2 * h)
        assert fd == pytest.approx(g.reshape(-1)[d], rel=1e-6, abs=1e-8)
        dg = (sim.gradient(x + e) - sim.gradient(x - e)).reshape(-1) / (2 * h)
        np.testing.assert_allclose(H[:, d], dg, rtol=1e-5, atol=1e-6)
    # Clamped per element: positive semi-definite.
    Hc = sim.hessian(x, projection="clamp")
    Hc = Hc.toarray() if hasattr(Hc, "toarray") else Hc
    assert np.linalg.eigvalsh(Hc).min() > -1e-10


def test_hessian_csr_arrays_without_scipy(monkeypatch):
    import builtins
    V, C, sim = small_system()
    real_import = builtins.__import__

    def no_scipy(name, *args, **kwargs):
        if name.startswith("scipy"):
            raise ImportError("no scipy here")
        return real_import(name, *args, **kwargs)

    with_scipy = sim.hessian(V * 1.1)
    monkeypatch.setattr(builtins, "__import__", no_scipy)
    for m in [k for k in list(__import__("sys").modules) if k.startswith("scipy")]:
        monkeypatch.delitem(__import__("sys").modules, m)
    indptr, indices, data = sim.hessian(V * 1.1)
    n = 3 * len(V)
    dense = np.zeros((n, n))
    for r in range(n):
        dense[r, indices[indptr[r]:indptr[r + 1]]] = data[indptr[r]:indptr[r + 1]]
    if hasattr(with_scipy, "toarray"):
        np.testing.assert_array_equal(dense, with_scipy.toarray())


def test_quasi_static_release_returns_to_rest():
    V, C, sim = small_system(pinned=np.arange(9), initial=None)
    x0 = V.copy()
    x0[9:] *= 1.3  # free vertices start stretched
    sim2 = snh.Simulation(V, C, SNH, np.arange(9), initial=x0, tolerance=1e-9)
    stats = sim2.step()
    assert stats["converged"] and stats["elastic_energy"] < 1e-12
    np.testing.assert_allclose(sim2.positions, V, atol=1e-8)
    assert sim2.free_dofs.tolist() == list(range(27, 3 * len(V)))


def test_multigrid_reports_its_chord_steps():
    # A box stretched by a tenth and let go: mg's last Newton iteration solves with the matrix it holds (a
    # chord step, after a step within 30 times the step rule) and the answer is CHOLMOD's to that rule.
    V, C, _ = snh.box("hex8", 10)
    pinned = np.flatnonzero(V[:, 1] == V[:, 1].min())
    x0 = V.copy()
    x0[:, 1] = V[:, 1].min() + 1.1 * (V[:, 1] - V[:, 1].min())
    runs = {}
    for solver in ("cholmod", "mg"):
        sim = snh.Simulation(V, C, SNH, pinned, initial=x0, solver=solver, tolerance=1e-14, step_tolerance=1e-5)
        runs[solver] = (sim.step(), sim.positions)
    assert runs["cholmod"][0]["chord_steps"] == 0
    assert runs["mg"][0]["converged"] and runs["mg"][0]["chord_steps"] >= 1
    np.testing.assert_allclose(runs["mg"][1], runs["cholmod"][1], atol=2e-4)  # 20 step rules


def test_bad_input():
    V, C, _ = snh.box("hex", 2)
    cases = [
        (dict(pinned=[0, 27]), r"pinned\[1\] = 27 is not a vertex index \(0 to 26\)"),
        (dict(pinned=[3, 3]), r"pinned\[1\] = 3: vertex 3 is pinned twice"),
        (dict(pinned=[0.5]), "pinned must be an array of integer vertex indices"),
        (dict(integrator="rk4"), "integrator must be quasi_static, backward_euler, bdf2 or tr_bdf2, got 'rk4'"),
        (dict(dt=0.0), "dt must be a finite number > 0, got 0"),
        (dict(density=math.nan), "density must be a finite number > 0, got nan"),
        (dict(gravity=[0, 1]), r"gravity must have shape \(3,\), got \(2,\)"),
        (dict(solver="magic"), "magic"),
        (dict(projection="half"), "projection must be none, clamp or abs, got 'half'"),
        (dict(initial=np.zeros((3, 3))), r"initial must have shape \(27, 3\), got \(3, 3\)"),
        (dict(first_guess=3), "first_guess must be a function"),
        (dict(initial_velocity=np.ones((27, 3))), "initial_velocity needs a dynamic integrator"),
        (dict(integrator="bdf2", initial_velocity=np.ones((2, 3))), r"initial_velocity must have shape \(27, 3\), got \(2, 3\)"),
        (dict(integrator="bdf2", initial_velocity=np.full((27, 3), math.nan)),
         r"initial_velocity entry \(0, 0\) is not a finite number: nan"),
    ]
    for kw, message in cases:
        pinned = kw.pop("pinned", None)
        with pytest.raises(ValueError, match=message):
            snh.Simulation(V, C, SNH, pinned, **kw)
    Vn = V.copy()
    Vn[4, 2] = math.inf
    with pytest.raises(ValueError, match=r"vertices entry \(4, 2\) is not a finite number: inf"):
        snh.Simulation(Vn, C, SNH)
    flat = V.copy()
    flat[:, 2] = 0.0
    with pytest.raises(ValueError, match="mesh: "):
        snh.Simulation(flat, C, SNH)
    with pytest.raises(TypeError, match=r"material must be an snh.Material \(made by snh.material\(\.\.\.\)\), got str"):
        snh.Simulation(V, C, "stable_neo_hookean")
    sim = snh.Simulation(V, C, SNH, [0, 1])
    with pytest.raises(ValueError, match=r"targets must have shape \(2, 3\), got \(3, 3\)"):
        sim.targets = np.zeros((3, 3))
    with pytest.raises(ValueError, match=r"x must have shape \(27, 3\)"):
        sim.energy(np.zeros((26, 3)))
    with pytest.raises(ValueError, match="set_targets: this simulation has no pinned vertices"):
        snh.Simulation(V, C, SNH).set_targets(np.zeros((0, 3)))


def test_non_convergence_is_a_runtime_error():
    V, C, _ = snh.box("hex", 2)
    top = np.flatnonzero(V[:, 1] == 1.0)
    sim = snh.Simulation(V, C, SNH, top, max_iterations=1, tolerance=1e-12)
    sim.targets = V[top] + [0, 2.0, 0]
    with pytest.raises(RuntimeError, match="step to t = 1: .*1"):
        sim.step()
    stats = sim.step(check=False)
    assert not stats["converged"] and stats["failure"]


def test_ctrl_c_interrupts_newton():
    # SIGINT arrives while Newton runs in C++ (an interval timer's SIGALRM handled as Python's SIGINT is): the
    # step stops at its next iteration, raises KeyboardInterrupt and leaves the state where it started.
    import time
    V, C, _ = snh.box("hex", 12)
    top = np.flatnonzero(V[:, 1] == 1.0)
    sim = snh.Simulation(V, C, SNH, top, tolerance=1e-12)
    sim.targets = V[top] + [0, 1.5, 0]
    previous = signal.signal(signal.SIGALRM, signal.default_int_handler)
    try:
        start = time.monotonic()
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        with pytest.raises(KeyboardInterrupt):
            sim.step()
        assert time.monotonic() - start < 5.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert sim.steps == 0 and np.array_equal(sim.positions, V)


def test_ctrl_c_in_a_callback():
    V, C, _ = snh.box("hex", 3)
    top = np.flatnonzero(V[:, 1] == 1.0)

    def interrupt(x, t):  # Ctrl-C arriving while the step is under way
        os.kill(os.getpid(), signal.SIGINT)
        return x

    sim = snh.Simulation(V, C, SNH, top, first_guess=interrupt)
    sim.targets = V[top] + [0, 0.5, 0]
    with pytest.raises(KeyboardInterrupt):
        sim.step()
    assert sim.steps == 0 and np.array_equal(sim.positions, V)


def test_ctrl_c_stops_run_scene(tmp_path):
    # As snh run on SIGINT: the run stops after the frame under way, keeps the frames and the stats ("interrupted"),
    # and Python sees KeyboardInterrupt. The signal is sent once frame 1 is on disk, the run having 400 more to go.
    import json
    import subprocess
    import sys
    import time
    scene = pin_scene(tmp_path)
    scene.update({"mesh": {"box": {"element": "hex", "res": 6}}, "end_time": 40, "frames": 400})
    script = ("import snh, sys, json\n"
              "try:\n"
              f"    snh.run_scene(json.loads(sys.argv[1]), report=False, quiet=True)\n"
              "except KeyboardInterrupt:\n"
              "    print('KeyboardInterrupt')\n")
    p = subprocess.Popen([sys.executable, "-c", script, json.dumps(scene)], stdout=subprocess.PIPE, text=True)
    out = tmp_path / "scene"
    deadline = time.monotonic() + 60
    while not (out / "001.obj").exists() and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.01)
    p.send_signal(signal.SIGINT)
    stdout, _ = p.communicate(timeout=60)
    assert p.returncode == 0 and stdout.strip() == "KeyboardInterrupt"
    stats = json.loads((out / "stats.json").read_text())
    assert stats["status"] == "interrupted"
    assert 2 <= len(list(out.glob("*.obj"))) < 401


def test_flesh_scene_from_a_dict(tmp_path):
    # scenes/hand_fist.json, coarse and short: bones drive the flesh; its render surface and USD stage are written.
    import json
    from conftest import SOURCE
    scene = json.loads((SOURCE / "scenes/hand_fist.json").read_text())
    scene["flesh"].update(model=str(SOURCE / "data/hand/left.glb"), resolution=8)
    scene.update(end_time=0.2, frames=2)
    scene.pop("output", None)
    r = snh.run_scene(scene, out=tmp_path / "hand", quiet=True, report=False)
    assert r["all_converged"] and r["frames"] == 3 and r["element"] == "hex8"
    assert (tmp_path / "hand" / "flesh.usda").exists() and (tmp_path / "hand" / "002.obj").exists()
    assert np.isfinite(r["final_positions"]).all()
    # The skin at the last frame, as the OBJ frames hold it (model order, 10 significant digits there).
    skin = r["final_surface"]
    assert skin.shape == (1360, 3) and r["surface_triangles"].shape == (2314, 3)
    obj = np.array(read_obj_vertices(tmp_path / "hand" / "surface" / "002.obj"), dtype=float)
    np.testing.assert_allclose(skin, obj, rtol=1e-9, atol=1e-12)


def test_run_scene_returns_the_warnings_the_log_prints(tmp_path):
    # The limb at resolution 24 bends its elbow 90 degrees: its default capsules press the flesh there inside out, its
    # tip bone binds nothing, and frames converge with cells inside out. quiet=True prints nothing, so the dict
    # carries each warning; they are the log's own "warning: " lines, as snh run prints them for the same scene.
    import json
    import re
    import subprocess
    from conftest import SOURCE
    scene = {"flesh": {"model": str(SOURCE / "tests/data/flesh/limb.gltf"), "resolution": 24}}
    r = snh.run_scene(scene, out=tmp_path / "pressed", quiet=True, report=False)
    assert r["all_converged"]
    w = r["warnings"]
    assert any(re.match(r"the bones press flesh inside out in \d+ frames: in frame 24 \(t = 1\) "
                        r"(shoulder>elbow and elbow>tip|elbow>tip and shoulder>elbow) carry", x) for x in w), w
    assert w[-1] and re.fullmatch(r"\d+ frames converged with elements turned inside out \(at most \d+, in frame \d+\)", w[-1]), w
    path = tmp_path / "limb.json"
    path.write_text(json.dumps(scene))
    log = subprocess.run([program("SNH_BIN"), "run", str(path), "--out", str(tmp_path / "cli"), "--no-report"], check=True,
                         capture_output=True, text=True, timeout=120).stdout
    assert [line[len("warning: "):] for line in log.splitlines() if line.startswith("warning: ")] == w[:-1]
    # Capsules that leave the flesh room: nothing pressed, no cell inside out (the tip bone still binds nothing).
    scene["flesh"]["radius_scale"] = 0.4
    r = snh.run_scene(scene, out=tmp_path / "roomy", quiet=True, report=False)
    assert r["all_converged"] and all(x.startswith("bone tip binds no volume vertex") for x in r["warnings"]), r["warnings"]
    # A clean run warns of nothing.
    box = {"mesh": {"box": {"element": "hex", "res": 2}}, "frames": 1}
    assert snh.run_scene(box, out=tmp_path / "box", quiet=True, report=False)["warnings"] == []


def test_a_dicts_paths_resolve_against_base_dir(tmp_path, monkeypatch):
    import json
    from conftest import SOURCE
    scene = json.loads((SOURCE / "scenes/hand_fist.json").read_text())
    scene["flesh"].update(model="hand/left.glb", resolution=6)  # relative: to base_dir, not the working directory
    scene.update(end_time=0.1, frames=1)
    scene.pop("output", None)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="hand/left.glb"):
        snh.run_scene(scene, out=tmp_path / "cwd", quiet=True, report=False)
    r = snh.run_scene(scene, base_dir=SOURCE / "data", out=tmp_path / "based", quiet=True, report=False)
    assert r["all_converged"] and r["final_surface"] is not None
    # A volume scene has no skin; a scene file's paths are its folder's, so base_dir is refused for one.
    assert snh.run_scene({"mesh": {"box": {"element": "hex", "res": 2}}, "frames": 1}, out=tmp_path / "box", quiet=True,
                         report=False)["final_surface"] is None
    with pytest.raises(ValueError, match="base_dir"):
        snh.run_scene(str(SOURCE / "scenes/hand_fist.json"), base_dir=tmp_path, out=tmp_path / "f", quiet=True)


def test_objects_made_without_init_raise_type_error():
    # Class.__new__(Class) gives an object whose C++ side was never made: every use raises TypeError (it used
    # to hand uninitialized memory to the methods: a segmentation fault, SIGILL or garbage).
    V, C, _ = snh.box("hex8", 2)
    for use in (lambda: snh.Simulation.__new__(snh.Simulation).step(1.0),
                lambda: snh.Simulation.__new__(snh.Simulation).positions,
                lambda: snh.Simulation.__new__(snh.Simulation).time,
                lambda: snh.Material.__new__(snh.Material).psi(np.eye(3)),
                lambda: snh.Material.__new__(snh.Material).name,
                lambda: snh.Simulation(V, C, snh.Material.__new__(snh.Material))):
        with pytest.raises(TypeError, match="made by __new__ without __init__"):
            use()
    # Made as documented, the same calls work.
    assert SNH.name == "stable_neo_hookean" and snh.Simulation(V, C, SNH).time == 0.0


def test_backward_euler_refuses_to_step_back_in_time():
    # A dynamic step to a time at or before the current one used to report converged, advance the physics by dt
    # and set the clock back: refused, the state untouched. Quasi-statically t only sets the pins: any t goes.
    V, C, _ = snh.box("hex8", 2)
    sim = snh.Simulation(V, C, SNH, integrator="backward_euler", dt=0.05, gravity=[0, -1, 0])
    sim.step(0.05)
    before = sim.positions.copy()
    for t in (0.05, 0.0, -5.0):
        with pytest.raises(ValueError, match="after the current time 0.05"):
            sim.step(t)
    assert sim.time == 0.05 and np.array_equal(sim.positions, before)
    quasi = snh.Simulation(V, C, SNH, pinned=[0])
    quasi.step(1.0)
    assert quasi.step(0.5)["converged"] and quasi.time == 0.5


def test_run_scene_takes_numpy_values_and_names_what_it_cannot_take(tmp_path):
    # NumPy scalars and arrays in a scene dict are the numbers and lists they hold (a json TypeError before);
    # None is a TypeError naming what a scene may be (pybind's internal cast error before).
    r = snh.run_scene({"mesh": {"box": {"element": "hex", "res": np.int64(2)}}, "frames": np.int32(1),
                       "gravity": np.array([0.0, -1.0, 0.0])}, out=tmp_path / "np", quiet=True, report=False)
    assert r["all_converged"] and r["frames"] == 2
    with pytest.raises(TypeError, match="scene must be a path"):
        snh.run_scene(None, quiet=True)
    with pytest.raises(ValueError, match="a value of type set cannot be written as JSON"):
        snh.run_scene({"mesh": {"box": {"element": "hex", "res": 2}}, "frames": {1}}, out=tmp_path / "set", quiet=True)


@pytest.mark.parametrize("integrator", ["bdf2", "tr_bdf2"])
def test_bdf2_carries_a_free_body_at_its_velocity(integrator):
    # No force: BDF2 (and its first, backward Euler step) and TR-BDF2 move every vertex by u t exactly.
    V, C, _ = snh.box("hex", 2)
    u = np.array([0.5, -2.0, 1.0])
    sim = snh.Simulation(V, C, SNH, integrator=integrator, dt=0.05, initial_velocity=np.tile(u, (len(V), 1)),
                         tolerance=1e-10)
    for k in range(1, 11):
        sim.step()
    assert sim.time == pytest.approx(0.5)
    np.testing.assert_allclose(sim.positions, V + 0.5 * u, atol=1e-12)
    np.testing.assert_allclose(sim.velocities, np.tile(u, (len(V), 1)), atol=1e-12)


def test_bdf2_keeps_the_vibration_backward_euler_damps():
    # A cube stretched and let go: over 8 s at dt 0.2 BDF2 keeps most of its swing, TR-BDF2 more, backward
    # Euler a tenth of it (docs/math.md sections 7.5 and 7.7).
    V, C, _ = snh.box("hex", 2)
    stretched = V * [1.3, 0.9, 1.1]
    kept = {}
    for integrator in ("backward_euler", "bdf2", "tr_bdf2"):
        sim = snh.Simulation(V, C, SNH, integrator=integrator, dt=0.2, initial=stretched, tolerance=1e-10)
        e0 = sim.energy()
        swing = 0.0
        for k in range(1, 41):
            sim.step()
            if k > 30:
                swing = max(swing, np.abs(sim.positions - V).max())
        kept[integrator] = swing / np.abs(stretched - V).max()
        assert sim.energy() < e0
    assert kept["bdf2"] > 0.55
    assert kept["tr_bdf2"] > kept["bdf2"]
    assert kept["backward_euler"] < 0.15


@pytest.mark.parametrize("integrator", ["backward_euler", "bdf2", "tr_bdf2"])
def test_pins_set_from_python_move_through_a_step(integrator):
    # Targets set before a step are where the pins are at its end; inside it (TR-BDF2's first stage, a step
    # retried in halves) they are on the way there, not already there. Pins moved at u: every integrator
    # ends each step with the pins at the speed u, and the stiffness damping that their speed feeds agrees.
    V, C, _ = snh.box("hex", 2)
    top = np.flatnonzero(V[:, 1] == 1.0)
    u = np.array([1.0, 0.0, 0.0])
    sim = snh.Simulation(V, C, SNH, top, integrator=integrator, dt=0.05, stiffness_damping=0.05, tolerance=1e-10)
    for k in range(1, 11):
        sim.targets = V[top] + u * 0.05 * k
        sim.step(0.05 * k)
        np.testing.assert_allclose(sim.velocities[top], np.tile(u, (len(top), 1)), atol=1e-9)
    np.testing.assert_allclose(sim.positions[top], V[top] + 0.5 * u, atol=1e-12)
