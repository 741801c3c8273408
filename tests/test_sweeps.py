"""Sweeps on Dask: the grid, validation, the same summary.csv on a LocalCluster and on a
scheduler and workers started as separate processes, failures recorded, resume, the command,
and the examples' science (apex ratio e², Haff's τ against Enskog)."""

import csv
import importlib.util
import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.scene import SceneError
from kinema.sweeps import members, parse_values

ROOT = Path(__file__).resolve().parent.parent
SWEEPS = ROOT / "examples" / "sweeps"
BIN = Path(sys.executable).parent


def gas(count=40, duration=0.3):
    """A small random gas: seeds matter (positions and velocities drawn from them)."""
    return {
        "world": {"dim": 3, "dt": 0.002, "method": "verlet", "duration": duration, "fps": 20.0},
        "particles": [
            {
                "type": "random",
                "lo": [0, 0, 0],
                "hi": [1, 1, 1],
                "count": count,
                "seed": 3,
                "min_distance": 0.1,
                "radius": 0.04,
                "velocity": {"speed": 1.0, "seed": 5},
            }
        ],
        "colliders": [{"type": "box", "lo": [0, 0, 0], "hi": [1, 1, 1]}],
        "collisions": {"restitution": 0.8},
        "output": {"video": False, "plot": False},
    }


def rows(folder):
    with open(Path(folder) / "summary.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_the_grid_is_the_product_of_the_values_and_the_seeds():
    grid = members(gas(), {"collisions.restitution": [0.5, 0.9], "world.dt": [0.002, 0.001]}, seeds=3)
    assert len(grid) == 12
    assert [m.values for m in grid[:3]] == [{"collisions.restitution": 0.5, "world.dt": 0.002}] * 3
    assert [m.seed for m in grid[:3]] == [0, 1, 2]
    assert grid[3].scene["world"]["dt"] == 0.001 and grid[3].scene["collisions"]["restitution"] == 0.5
    # every seed of the scene is the member's own: different members, the same for the same s
    seeds = {(m.scene["particles"][0]["seed"], m.scene["particles"][0]["velocity"]["seed"]) for m in grid}
    assert len(seeds) == 3
    again = members(gas(), {"collisions.restitution": [0.5, 0.9], "world.dt": [0.002, 0.001]}, seeds=3)
    assert [m.scene for m in again] == [m.scene for m in grid]
    assert len({m.name for m in grid}) == 12


def test_bad_keys_and_values_are_named_before_anything_runs(tmp_path):
    with pytest.raises(SceneError, match=r"collisions.\w*: .*restitution|restitution.*1\.5|1\.5"):
        members(gas(), {"collisions.restitution": [0.5, 1.5]})
    with pytest.raises(SceneError, match="collisions.restitushun"):
        members(gas(), {"collisions.restitushun": [0.5]})
    with pytest.raises(SceneError, match=r"particles.4 is not an entry \(the scene has 1\)"):
        members(gas(), {"particles.4.radius": [0.1]})
    with pytest.raises(SceneError, match="has no values"):
        members(gas(), {"world.dt": []})
    with pytest.raises(SceneError):
        kinema.sweep(gas(), {"world.dt": [-1.0]}, out=tmp_path / "s")
    assert not (tmp_path / "s" / "members").exists()  # nothing ran


def test_values_from_the_command_line_are_toml():
    assert parse_values("0.5,0.7,1") == [0.5, 0.7, 1]
    assert parse_values('verlet,"rk4",true') == ["verlet", "rk4", True]
    assert parse_values("[0, 0, 1],[1, 0, 0]") == [[0, 0, 1], [1, 0, 0]]
    with pytest.raises(ValueError, match="empty value"):
        parse_values("0.5,,0.7")


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_local_cluster_and_a_cluster_started_by_hand_give_the_same_summary(tmp_path):
    vary = {"collisions.restitution": [0.6, 0.9]}
    local = kinema.sweep(gas(), vary, seeds=2, out=tmp_path / "local", workers=2, progress=False)
    assert not local.failed and len(local.rows) == 4
    port = _free_port()
    env = {**os.environ, "RAYON_NUM_THREADS": "1"}
    scheduler = subprocess.Popen(
        [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], env=env, stderr=subprocess.DEVNULL
    )
    worker = subprocess.Popen(
        [str(BIN / "dask"), "worker", f"tcp://127.0.0.1:{port}", "--nworkers", "2", "--nthreads", "1", "--no-dashboard"], env=env, stderr=subprocess.DEVNULL
    )
    try:
        from distributed import Client

        with Client(f"tcp://127.0.0.1:{port}", timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
            remote = kinema.sweep(gas(), vary, seeds=2, out=tmp_path / "remote", client=client, progress=False)
            hosts = {r["pid"] for r in _timings(tmp_path / "remote")}
    finally:
        for p in (worker, scheduler):
            p.terminate()
            p.wait(timeout=30)
    assert len(hosts) >= 1 and not remote.failed
    assert (tmp_path / "local" / "summary.csv").read_bytes() == (tmp_path / "remote" / "summary.csv").read_bytes()
    # the members differ by seed and by e, so the identity says something
    finals = [float(r["final_kinetic"]) for r in rows(tmp_path / "local")]
    assert len(set(finals)) == 4
    # and each member's trajectory is there, readable
    traj = kinema.load_trajectory(tmp_path / "remote" / "members" / local.members[0].name / "trajectory.h5")
    assert traj.positions.shape[1] == 40


def _timings(folder):
    with open(Path(folder) / "timings.csv", newline="") as f:
        return list(csv.DictReader(f))


def picky(traj, world):
    """A measurement that fails for one member (module level: the workers import it)."""
    if world.collisions["restitution"] == 0.7:
        raise RuntimeError("no measurement at e = 0.7")
    return {"top": float(np.nanmax(traj.positions[..., 2]))}


def test_a_failing_member_is_recorded_and_the_others_finish(tmp_path):
    result = kinema.sweep(gas(), {"collisions.restitution": [0.5, 0.7, 0.9]}, measure=picky, out=tmp_path / "s", workers=2, progress=False)
    assert [r["error"] for r in result.failed] == ["RuntimeError: no measurement at e = 0.7"]
    table = rows(tmp_path / "s")
    assert [r["error"] for r in table] == ["", "RuntimeError: no measurement at e = 0.7", ""]
    assert table[0]["top"] and table[2]["top"] and not table[1]["top"]
    assert "no measurement" in (tmp_path / "s" / "members" / result.members[1].name / "error.txt").read_text()


def test_a_sweep_run_again_skips_finished_members(tmp_path):
    vary = {"collisions.restitution": [0.5, 0.9]}
    first = kinema.sweep(gas(), vary, out=tmp_path / "s", workers=2, progress=False, plot=False)
    stamps = {m.name: (tmp_path / "s" / "members" / m.name / "result.json").stat().st_mtime_ns for m in first.members}
    # as if the sweep had been stopped before the second member finished
    (tmp_path / "s" / "members" / first.members[1].name / "result.json").unlink()
    time.sleep(0.01)
    again = kinema.sweep(gas(), vary, out=tmp_path / "s", progress=False, plot=False)
    assert (tmp_path / "s" / "members" / first.members[0].name / "result.json").stat().st_mtime_ns == stamps[first.members[0].name]
    assert (tmp_path / "s" / "members" / first.members[1].name / "result.json").stat().st_mtime_ns != stamps[first.members[1].name]
    assert again.rows == first.rows


def test_a_sweep_run_again_with_other_settings_runs_its_members_again(tmp_path):
    # Before, a rerun into the same folder reused every member that had a result.json: with
    # another duration, summary.csv kept the old run's frames (issue 26). A member is reused
    # only when its key (scene and seed, duration, measure, kinema version) is the same.
    vary = {"collisions.restitution": [0.5, 0.9]}
    out = tmp_path / "s"
    kinema.sweep(gas(duration=0.3), vary, out=out, progress=False, plot=False, workers=1)
    assert [r["frames"] for r in rows(out)] == ["7", "7"]  # 0.3 s at 20 fps, both ends
    kinema.sweep(gas(duration=0.3), vary, out=out, duration=0.1, progress=False, plot=False, workers=1)
    assert [r["frames"] for r in rows(out)] == ["3", "3"]
    # a changed scene (another count of particles) runs again too; the same one is reused
    changed = kinema.sweep(gas(count=30, duration=0.3), vary, out=out, duration=0.1, progress=False, plot=False, workers=1)
    stamps = [(out / "members" / m.name / "result.json").stat().st_mtime_ns for m in changed.members]
    again = kinema.sweep(gas(count=30, duration=0.3), vary, out=out, duration=0.1, progress=False, plot=False, workers=1)
    assert [(out / "members" / m.name / "result.json").stat().st_mtime_ns for m in again.members] == stamps
    assert again.rows == changed.rows
    # a measure is part of the key: adding one runs the members again, with its column
    measured = kinema.sweep(gas(count=30, duration=0.3), vary, out=out, duration=0.1, measure=picky_top, progress=False, plot=False, workers=1)
    assert all("top" in r for r in measured.rows)


def picky_top(traj, world):
    return {"top": float(traj.positions[-1][:, 2].max())}


def test_a_key_varied_twice_is_an_error(tmp_path):
    scene = tmp_path / "gas.toml"
    kinema.scene.Scene.from_dict(gas()).to_toml(scene)
    res = subprocess.run(
        [str(BIN / "kinema"), "sweep", str(scene), "--vary", "collisions.restitution=0.5", "--vary", "collisions.restitution=0.9", "-o", str(tmp_path / "s")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 2 and "collisions.restitution is varied twice" in res.stderr, res.stderr
    assert not (tmp_path / "s").exists()


def test_the_local_cluster_listens_on_loopback_only(tmp_path, monkeypatch):
    # Before, the dashboard (workers, logs, call stacks) listened on 0.0.0.0 (issue 26): every
    # socket the scheduler and its workers listen on is on 127.0.0.1.
    import distributed
    import psutil

    listening = []
    real = distributed.LocalCluster

    def spy(*args, **kwargs):
        cluster = real(*args, **kwargs)
        me = psutil.Process()
        for proc in [me, *me.children(recursive=True)]:
            listening.extend(c.laddr.ip for c in proc.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN)
        return cluster

    monkeypatch.setattr(distributed, "LocalCluster", spy)
    kinema.sweep(gas(), {"collisions.restitution": [0.5, 0.9]}, out=tmp_path / "s", workers=2, progress=False, plot=False)
    assert len(listening) >= 3 and set(listening) == {"127.0.0.1"}, listening


def test_the_command_runs_a_sweep(tmp_path):
    scene = tmp_path / "gas.toml"
    kinema.scene.Scene.from_dict(gas()).to_toml(scene)
    out = tmp_path / "s"
    res = subprocess.run(
        [str(BIN / "kinema"), "sweep", str(scene), "--vary", "collisions.restitution=0.5,0.9", "--seeds", "2", "-o", str(out), "--workers", "2"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    assert "4 members, 0 failed" in res.stdout
    assert len(rows(out)) == 4 and (out / "summary.png").stat().st_size > 10_000
    bad = subprocess.run([str(BIN / "kinema"), "sweep", str(scene), "--vary", "collisions.restitution"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "use KEY=V1,V2" in bad.stderr


def _load(name):
    spec = importlib.util.spec_from_file_location(name, SWEEPS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    import cloudpickle

    cloudpickle.register_pickle_by_value(module)  # the workers cannot import it by name
    return module


def test_bounce_apex_ratios_are_e_squared(tmp_path):
    # Newton's law at the floor, u⁺ = −e u⁻: the first apex is e² of the drop height, exactly
    # (velocity Verlet integrates the parabola exactly; the impact time is found exactly).
    r = _load("bounce").main(tmp_path)
    np.testing.assert_allclose(r["ratio"], r["e"] ** 2, rtol=0, atol=1e-12)
    assert (tmp_path / "apex_ratio.png").stat().st_size > 10_000


def test_haff_time_matches_enskog_in_a_dilute_gas(tmp_path):
    # Haff's law T = T₀/(1 + t/τ)² with Enskog's 1/τ = (1 − e²) ω(T₀)/6: within 4 % at
    # n σ³ = 0.05 for e = 0.7 … 0.9 (measured 1–3 %: molecular chaos holds only so far, and
    # Enskog's collision frequency is itself 1 % high at this density), a small gas (512) and
    # 2 seeds to keep the test short.
    haff = _load("haff")
    r = haff.main(tmp_path, ncell=8, seeds=2, duration=40.0)
    for e, err in r["mean_relative_error"].items():
        assert abs(err) < 0.04, (e, err)
    assert (tmp_path / "haff_tau.png").stat().st_size > 10_000
    shutil.rmtree(tmp_path / "members")


def test_a_member_whose_worker_dies_is_run_again(tmp_path):
    # The first attempt kills its own worker process (as an out-of-memory kill or a lost node
    # would); Dask runs the member again on a worker, and the sweep ends with every row.
    marker = tmp_path / "died-once"

    def die_once(traj, world):
        if not marker.exists():
            marker.write_text("the first attempt's worker died here")
            os._exit(1)
        return {"top": float(np.nanmax(traj.positions[..., 2]))}

    result = kinema.sweep(gas(), {"collisions.restitution": [0.5, 0.9]}, measure=die_once, out=tmp_path / "s", workers=2, progress=False, plot=False)
    assert marker.exists() and not result.failed
    assert all(r["top"] > 0 for r in result.rows)


def test_the_summary_plot_says_its_units_and_drops_what_never_changes():
    # summary.png's panels: each measurement against each numeric varied key, labelled with
    # its unit (J, s, ...); the frames of a fixed duration are equal in every member and get
    # no panel; a measure's own column keeps its bare name.
    from kinema.sweeps import _figure

    rows = [
        {
            "member": f"m{k}",
            "world.dt": dt,
            "seed": s,
            "final_kinetic": 1.0 + dt * s,
            "energy_lost": 0.1 * s,
            "frames": 61,
            "impacts": 3 + s,
            "spread": 0.5 * s,
            "error": "",
        }
        for k, (dt, s) in enumerate((dt, s) for dt in (0.001, 0.002) for s in range(3))
    ]
    fig = _figure(rows, ["world.dt"])
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    assert labels == [("world.dt (s)", "final_kinetic (J)"), ("world.dt (s)", "energy_lost (J)"), ("world.dt (s)", "impacts"), ("world.dt (s)", "spread")], (
        labels
    )
    assert _figure([{**r, "final_kinetic": 1.0, "energy_lost": 0.0, "impacts": 0, "spread": 0.0} for r in rows], ["world.dt"]) is None


def forever(traj, world):
    return {"forever": float("inf"), "undefined": float("nan")}


def test_the_sweeps_json_files_are_standard_json_and_read_back(tmp_path):
    # Before, sweep.json held the bare token Infinity (an emitter's lifetime), which JSON
    # parsers other than Python's refuse (RFC 8259 has no infinity). Python's parse_constant
    # is called for exactly those tokens: a strict parser here.
    def strict(token):
        raise ValueError(f"not standard JSON: {token}")

    scene = gas(count=5, duration=0.1)
    scene["emitters"] = [{"rate": 10.0, "center": [0.5, 0.5, 0.8], "particle_radius": 0.04, "mass": 1.0}]
    out = tmp_path / "s"
    first = kinema.sweep(scene, {"collisions.restitution": [0.5]}, measure=forever, out=out, progress=False, plot=False)
    asked = json.loads((out / "sweep.json").read_text(), parse_constant=strict)
    assert asked["scene"]["emitters"][0]["lifetime"] == "Infinity"
    assert kinema.sweeps.read_json(out / "sweep.json")["scene"]["emitters"][0]["lifetime"] == float("inf")
    result = out / "members" / first.members[0].name / "result.json"
    assert json.loads(result.read_text(), parse_constant=strict)["row"]["forever"] == "Infinity"
    # run again: the finished member is read back from its result.json, numbers and all
    stamp = result.stat().st_mtime_ns
    again = kinema.sweep(scene, {"collisions.restitution": [0.5]}, measure=forever, out=out, progress=False, plot=False)
    assert result.stat().st_mtime_ns == stamp
    assert again.rows[0]["forever"] == float("inf") and np.isnan(again.rows[0]["undefined"])
    assert first.rows[0]["forever"] == float("inf")


MEASURE = '''
def top(traj, world):
    """The highest centre at the end, m, and the restitution the member ran with."""
    return {"top": float(traj.positions[-1][:, 2].max()), "e": world.collisions["restitution"]}
'''


def test_the_command_takes_a_measure_by_module_and_function(tmp_path):
    # `kinema sweep --measure MODULE:FUNCTION`: a module in the folder the command runs in,
    # run by two worker processes (which get it by value), its values in each member's row.
    scene = tmp_path / "gas.toml"
    kinema.scene.Scene.from_dict(gas(count=8, duration=0.1)).to_toml(scene)
    (tmp_path / "mymeasures.py").write_text(MEASURE)
    args = [str(BIN / "kinema"), "sweep", str(scene), "--vary", "collisions.restitution=0.5,0.9", "--workers", "2"]
    res = subprocess.run([*args, "--measure", "mymeasures:top", "-o", "s"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    table = rows(tmp_path / "s")
    assert [float(r["e"]) for r in table] == [0.5, 0.9]
    assert all(0.0 < float(r["top"]) < 1.0 for r in table)
    # a file by its path, from elsewhere
    res = subprocess.run([*args, "--measure", f"{tmp_path / 'mymeasures.py'}:top", "-o", str(tmp_path / "f")], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert [float(r["e"]) for r in rows(tmp_path / "f")] == [0.5, 0.9]
    # what cannot be had is exit 2, one line naming the option and the value, before any work
    for given, said in [
        ("mymeasures", "use MODULE:FUNCTION or FILE.py:FUNCTION"),
        ("mymeasures:bottom", "mymeasures has no function bottom"),
        ("nomodule:top", "cannot import nomodule: ModuleNotFoundError"),
        ("missing.py:top", "there is no file missing.py"),
    ]:
        bad = subprocess.run([*args, "--measure", given, "-o", "x"], cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert bad.returncode == 2 and f"--measure {given!r}: {said}" in bad.stderr, bad.stderr
        assert not (tmp_path / "x").exists()
