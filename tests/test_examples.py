"""Every example in examples/ runs, and what it shows is checked against its closed form."""

import importlib.util
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_example_is_tested():
    assert sorted(p.stem for p in EXAMPLES.glob("*.py")) == ["maxwell_gas", "pendulum_periods", "stiff_decay"]


def test_stiff_decay(tmp_path):
    r = load("stiff_decay").main(tmp_path)
    # explicit limits are 2/1000 (Euler) and 2.785/1000 (RK4); implicit Euler has none
    assert abs(r["limits"]["euler"] - 0.002) < 1e-15
    assert abs(r["limits"]["rk4"] - 2.785293563405282e-3) < 1e-12
    assert np.isinf(r["limits"]["implicit_euler"])
    # backward Euler on the slow manifold: error ~ h |y''| / |λ| ~ 0.05 / 1000 (t >= 0.1)
    assert r["implicit_error"] < 1e-3
    assert r["explicit_max"] > 1e100  # RK4 at 18x its stable step
    assert r["fine_max"] <= 2.0  # RK4 below its limit is stable: |y| never exceeds y(0)
    assert (tmp_path / "stiff_decay.png").stat().st_size > 10_000


def test_pendulum_periods(tmp_path):
    r = load("pendulum_periods").main(tmp_path)
    # Verlet's period error is O(h²) = O(1e-6); the exact period is 4K(k²)/ω₀
    assert r["max_relative_error"] < 1e-5
    assert r["nfev"] == r["nsteps"] + 1  # one batched call per step
    assert (tmp_path / "pendulum_periods.png").stat().st_size > 10_000


def test_maxwell_gas_relaxes_to_maxwell_boltzmann(tmp_path):
    r = load("maxwell_gas").main(tmp_path)
    n = r["speed"].shape[1]
    # Equipartition with the speed every sphere starts with: a² = ⟨v²⟩/3 = (1 m/s)²/3, less
    # the drift removed at the start.
    assert abs(r["a"] - np.sqrt(1.0 / 3.0)) < 0.01
    # Kolmogorov–Smirnov distance to f(v) = √(2/π) v²/a³ exp(−v²/2a²): a single speed at
    # t = 0 is far from it (D ≈ 0.59); after a few collision times the last frame passes the
    # KS test at the 1 % level (critical D = 1.63/√n for n samples).
    assert r["ks"][0] > 0.5
    assert r["ks"][-1] < 1.63 / np.sqrt(n)
    late = r["t"] >= 1.0
    assert r["ks"][late].max() < 1.63 / np.sqrt(n)
    # the gas is closed: energy and momentum stay what they were
    traj = r["trajectory"]
    assert abs(traj.total[-1] - traj.total[0]) < 1e-9 * traj.total[0]
    assert np.abs(traj.momentum).max() < 1e-10
    assert (tmp_path / "maxwell_gas.png").stat().st_size > 10_000
