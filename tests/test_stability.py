"""kinema.stability against the theory of the test equation p' = λp."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import kinema
from kinema import stability

RK4_REAL_LIMIT = -2.785293563405282  # the negative real root of 1 + z + z²/2 + z³/6 + z⁴/24 = 1


def test_euler_and_midpoint_real_interval_is_minus_two_to_zero():
    for m in ("euler", "midpoint", "heun"):
        lo, hi = stability.real_interval(m)
        assert abs(lo + 2.0) < 1e-12 and hi == 0.0, m


def test_rk4_limits():
    assert abs(stability.real_interval("rk4").lo - RK4_REAL_LIMIT) < 1e-9
    lo, hi = stability.imag_interval("rk4")
    assert abs(hi - 2 * np.sqrt(2)) < 1e-9 and abs(lo + 2 * np.sqrt(2)) < 1e-9


def test_rk4_real_limit_is_where_the_polynomial_reaches_minus_one():
    # On the real axis RK4's R stays positive (its minimum is about 0.27 near x = -1.6), so
    # the boundary is where R(x) = +1 again: z + z²/2 + z³/6 + z⁴/24 = 0.
    r = stability.amplification("rk4", RK4_REAL_LIMIT)
    assert abs(r - 1.0) < 1e-12
    x = RK4_REAL_LIMIT
    assert abs(1 + x / 2 + x**2 / 6 + x**3 / 24) < 1e-12


def test_euler_and_midpoint_have_no_imaginary_interval():
    for m in ("euler", "midpoint"):
        assert stability.imag_interval(m).empty
        assert stability.max_step(m, 1j) == 0.0


def test_implicit_euler_is_stable_on_the_whole_left_half_plane():
    re, im = np.meshgrid(np.linspace(-50, 0, 51), np.linspace(-50, 50, 101))
    lam = (re + 1j * im).ravel()
    lam = lam[lam != 0]
    assert np.all(np.isinf(stability.max_step("implicit_euler", lam)))
    assert np.all(np.abs(stability.amplification("implicit_euler", lam)) <= 1.0)
    assert stability.real_interval("implicit_euler") == (-np.inf, 0.0)


def test_symplectic_methods_are_stable_for_h_omega_up_to_two():
    for m in ("verlet", "symplectic_euler"):
        lo, hi = stability.imag_interval(m)
        assert lo == -2.0 and hi == 2.0
        assert stability.real_interval(m).empty


def test_amplification_matches_the_closed_forms():
    z = np.array([-1.5 + 0.5j, 0.3 - 2j, -0.01 + 0j, 2.5j])
    np.testing.assert_allclose(stability.amplification("euler", z), 1 + z, rtol=1e-15)
    np.testing.assert_allclose(stability.amplification("midpoint", z), 1 + z + z**2 / 2, rtol=1e-15)
    np.testing.assert_allclose(stability.amplification("rk4", z), 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24, rtol=1e-14)
    np.testing.assert_allclose(stability.amplification("implicit_euler", z), 1 / (1 - z), rtol=1e-15)
    assert stability.amplification("rk4", np.zeros((2, 3))).shape == (2, 3)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(min_value=1, max_value=5).flatmap(
        lambda s: st.tuples(
            st.lists(st.floats(-2, 2), min_size=s * (s - 1) // 2, max_size=s * (s - 1) // 2),
            st.lists(st.floats(0.01, 1), min_size=s, max_size=s),
        )
    ),
    st.complex_numbers(max_magnitude=4, allow_nan=False, allow_infinity=False),
)
def test_tableau_amplification_is_one_plus_z_b_inverse_i_minus_za_one(coefs, z):
    # Property: for any explicit tableau, R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙 (computed here by a
    # dense solve, in the engine by the terminating Neumann series).
    lower, w = coefs
    s = len(w)
    a = np.zeros((s, s))
    a[np.tril_indices(s, -1)] = lower
    b = np.array(w) / np.sum(w)
    tab = kinema.ButcherTableau(a.tolist(), b.tolist(), a.sum(axis=1).tolist(), order=1)
    expected = 1 + z * b @ np.linalg.solve(np.eye(s) - z * a, np.ones(s))
    got = stability.amplification(tab, z)
    assert abs(got - expected) <= 1e-9 * max(1.0, abs(expected))


def _run_test_equation(method, lam, h, steps):
    """p' = λp as a real 2-D system [Re p, Im p]; max |p| over the run (inf if it overflowed)."""
    a = np.array([[lam.real, -lam.imag], [lam.imag, lam.real]])
    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", kinema.SolverWarning)
        sol = kinema.solve(lambda t, y: a @ y, [1.0, 0.0], (0.0, steps * h), h=h, method=method)
    if not sol.success:
        return np.inf
    return np.max(np.hypot(sol.y[:, 0], sol.y[:, 1]))


@pytest.mark.parametrize(
    "method, lam",
    [
        ("euler", -1.0 + 0j),
        ("euler", -1.0 + 0.8j),
        ("midpoint", -3.0 + 0j),
        ("midpoint", -1.0 + 1.0j),
        ("heun", -2.0 + 1.5j),
        ("rk4", -1.0 + 0j),
        ("rk4", 1j),
        ("rk4", -0.5 + 2.0j),
        ("rk45", -1.0 + 0j),
    ],
)
def test_a_step_two_percent_below_the_limit_is_bounded_and_two_percent_above_grows(method, lam):
    # Behaviour, not formulas: |p_N| = |R(hλ)|^N |p_0|. Below the limit |R| <= 1 (bounded for
    # 10,000 steps); above it |R| > 1 and the solution grows without bound. rk45 adapts its
    # step, so its Dormand-Prince tableau is run with the fixed step instead.
    if method == "rk45":
        method = kinema.ButcherTableau.of("rk45")
    h_max = stability.max_step(method, lam)
    assert 0 < h_max < np.inf
    assert _run_test_equation(method, lam, 0.98 * h_max, 10_000) <= 1.0 + 1e-12
    assert _run_test_equation(method, lam, 1.02 * h_max, 10_000) > 1e3


@pytest.mark.parametrize("method", ["verlet", "symplectic_euler"])
def test_symplectic_step_limit_on_the_oscillator(method):
    omega = 3.0
    h_max = stability.max_step(method, 1j * omega)
    assert abs(h_max - 2.0 / omega) < 1e-12

    def amplitude(h):
        sol = kinema.solve_second_order(lambda t, x, v: -(omega**2) * x, [1.0], [0.0], (0.0, 10_000 * h), h=h, method=method)
        return np.max(np.abs(sol.x)) if sol.success else np.inf

    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", kinema.SolverWarning)
        # bounded (the modified energy is conserved; amplitude grows by at most 1/sqrt(1 - (hω/2)^2))
        assert amplitude(0.98 * h_max) < 10.0
        assert amplitude(1.02 * h_max) > 1e3


def test_max_step_is_inverse_in_lambda():
    assert abs(stability.max_step("euler", -10.0) - 0.2) < 1e-14
    lams = np.array([-1.0, -4.0, -100.0])
    np.testing.assert_allclose(stability.max_step("rk4", lams), -RK4_REAL_LIMIT / np.abs(lams), rtol=1e-9)


def test_plot_regions_draws_every_method(tmp_path):
    import matplotlib.pyplot as plt

    ax = stability.plot_regions(["euler", "rk4", "implicit_euler"])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["euler", "rk4", "implicit_euler"]
    assert ax.get_aspect() == 1.0
    ax.figure.savefig(tmp_path / "r.png")
    plt.close(ax.figure)
    assert (tmp_path / "r.png").stat().st_size > 10_000


def test_oscillator_limits_undamped_equal_the_imaginary_intervals():
    assert abs(stability.max_step_oscillator("verlet", 10.0) - 0.2) < 1e-9
    assert abs(stability.max_step_oscillator("rk4", 10.0) - 2 * np.sqrt(2) / 10) < 1e-9
    assert stability.max_step_oscillator("euler", 10.0) == 0.0
    # forward Euler on the damped oscillator: |1 + hλ| ≤ 1 with λ = ω(−ζ ± i√(1−ζ²)) gives hω ≤ 2ζ
    assert abs(stability.max_step_oscillator("euler", 10.0, 0.1) - 0.02) < 1e-12


@pytest.mark.parametrize("method", ["verlet", "symplectic_euler", "rk4"])
def test_damped_oscillator_limit_is_where_the_motion_starts_to_grow(method):
    omega, zeta = 10.0, 0.1
    h_max = stability.max_step_oscillator(method, omega, zeta)
    assert stability.oscillator_amplification(method, 0.98 * h_max, omega, zeta) <= 1.0
    assert stability.oscillator_amplification(method, 1.02 * h_max, omega, zeta) > 1.0

    def last_over_first(h):
        with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
            warnings.simplefilter("ignore", kinema.SolverWarning)
            sol = kinema.solve_second_order(lambda t, x, v: -(omega**2) * x - 2 * zeta * omega * v, [1.0], [0.0], (0, 10_000 * h), h=h, method=method)
        if not sol.success:
            return np.inf
        x = np.abs(sol.x[:, 0])
        return x[-1000:].max() / x[:1000].max()

    assert last_over_first(0.98 * h_max) <= 1.0
    assert last_over_first(1.02 * h_max) > 10.0


def test_oscillator_bad_input():
    with pytest.raises(ValueError, match="omega = -1.0 is invalid"):
        stability.max_step_oscillator("verlet", -1.0)
    with pytest.raises(ValueError, match="zeta = -0.5 is invalid"):
        stability.max_step_oscillator("verlet", 1.0, -0.5)


@pytest.mark.parametrize("friction", [0.0, 0.5])
def test_the_stability_warning_advises_only_the_methods_the_world_accepts(friction):
    # a spring–dashpot pair at rest: its standby contact (ω₀² = k / m*) limits Verlet to
    # dt <= 2/ω₀ = 2 √(0.5 / 1e4) = 0.0141 s; with friction the world steps with Verlet only
    # (a ValueError for any other method), so implicit_euler is no advice there
    w = kinema.World(dt=0.05)
    w.set_collisions(model="spring_dashpot", stiffness=1e4, restitution=1.0, friction=friction)
    w.add_particles([[0, 0, 0], [0.5, 0, 0]], mass=1.0, radius=0.1)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        w.step(1)
    said = [str(g.message) for g in got if issubclass(g.category, kinema.StabilityWarning)]
    assert len(said) == 1 and "dt = 0.05 s exceeds the stable-step advisor's limit 0.01414 s" in said[0]
    if friction:
        assert "implicit_euler" not in said[0] and "reduce dt (contacts with friction under a force model step with method='verlet' only)" in said[0]
        other = kinema.World(dt=0.05, method="implicit_euler")
        other.set_collisions(model="spring_dashpot", stiffness=1e4, friction=friction)
        other.add_particles([[0, 0, 0], [0.5, 0, 0]], mass=1.0, radius=0.1)
        with pytest.raises(ValueError, match="step with method='verlet' only"):
            other.step(1)
    else:
        assert "reduce dt or use method='implicit_euler'" in said[0]


# -- stable sets with no area (issue 48: Verlet's and symplectic Euler's plots were empty) ----


@pytest.mark.parametrize("method", ["verlet", "symplectic_euler"])
def test_the_symplectic_methods_are_stable_on_the_imaginary_segment_only(method):
    assert stability.segments(method) == [(-2j, 2j)]
    y = np.linspace(-2.0, 2.0, 401)
    assert np.all(np.abs(stability.amplification(method, 1j * y)) <= 1.0 + 1e-12)
    # just off the axis, on either side, and just beyond ±2i: unstable
    for off in (1e-3, -1e-3, 0.3, -0.3):
        assert np.all(np.abs(stability.amplification(method, off + 1j * y)) > 1.0)
    assert np.all(np.abs(stability.amplification(method, 1j * np.array([-2.01, 2.01, 3.0]))) > 1.0)


@pytest.mark.parametrize("method", ["euler", "midpoint", "heun", "rk4", "rk45", "implicit_euler"])
def test_a_region_with_an_area_has_no_segments(method):
    assert stability.segments(method) == []


def test_plot_regions_draws_the_segment_of_a_method_with_no_area():
    import matplotlib.pyplot as plt

    ax = stability.plot_regions(["euler", "verlet", "symplectic_euler"])
    drawn = {line.get_gid(): line for line in ax.get_lines() if (line.get_gid() or "").startswith("segment:")}
    assert set(drawn) == {"segment:verlet", "segment:symplectic_euler"}
    for line in drawn.values():
        np.testing.assert_array_equal(line.get_xdata(), [0.0, 0.0])
        np.testing.assert_array_equal(line.get_ydata(), [-2.0, 2.0])
        assert line.get_linewidth() >= 2.0
    # both show: the one drawn on top is narrower
    assert drawn["segment:symplectic_euler"].get_linewidth() < drawn["segment:verlet"].get_linewidth()
    assert drawn["segment:symplectic_euler"].get_zorder() > drawn["segment:verlet"].get_zorder()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["euler", "verlet: only [−2i, 2i]", "symplectic_euler: only [−2i, 2i]"]
    plt.close(ax.figure)


def test_each_filled_region_shows_its_legend_colour():
    """Euler's disc lies inside midpoint's, RK4's and RK45's regions: translucent fills mixed
    their colours there, so the disc did not show the colour of its legend patch."""
    import matplotlib.pyplot as plt

    methods = ["euler", "midpoint", "rk4", "rk45", "implicit_euler"]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=100)
    stability.plot_regions(methods, ax=ax)
    faces = dict(zip(methods, (h.get_facecolor() for h in ax.get_legend().legend_handles), strict=True))
    fig.canvas.draw()
    pixels = np.asarray(fig.canvas.buffer_rgba())
    # a point of each region outside the smaller ones (and off the axes' lines and outlines)
    for method, z in (("euler", -1.0 + 0.5j), ("midpoint", -1.5 + 1.2j), ("rk4", -2.5 + 0.3j), ("rk45", -3.1 + 0.3j)):
        x, y = ax.transData.transform((z.real, z.imag))
        seen = pixels[int(round(pixels.shape[0] - y)), int(round(x)), :3] / 255.0
        np.testing.assert_allclose(seen, faces[method][:3], atol=2 / 255, err_msg=method)
        assert faces[method][3] == 1.0
    plt.close(fig)
