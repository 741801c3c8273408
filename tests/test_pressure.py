"""What contacts do, reported: the pressure tensor of a periodic world (``Trajectory.pressure``:
kinetic Σ m v ⊗ v / V plus the virial of the pair impulses and forces per unit time and
volume), the impacts of each frame (``Trajectory.impacts``), and the spring–dashpot model's
books in ``collision_stats`` (contacts, contacts begun as impacts, the dashpots' dissipation,
the virial).

Closed forms: an ideal gas's p V = N k T = 2/3 E_kin (the kinetic part alone, exactly); the
elastic hard-sphere gas's compressibility factor Z = p V / (N k T) against Carnahan &
Starling (1969), Z = (1 + φ + φ² − φ³) / (1 − φ)³, within 2 % at φ = 0.3 as the issue asks;
a damped linear contact's dissipated energy ½ m* u² (1 − e²).
"""

import numpy as np
import pytest

import kinema


def periodic_gas(phi, n_side, model="impulse", event_driven=True, seed=1):
    """Spheres of diameter 1 m and mass 1 kg on a simple cubic lattice filling a periodic cube
    to the packing fraction ``phi``, with random velocities of zero total momentum."""
    d = 1.0
    a = d * (np.pi / (6 * phi)) ** (1 / 3)
    side = n_side * a
    g = (np.arange(n_side) + 0.5) * a
    x = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    rng = np.random.default_rng(seed)
    v = rng.normal(0.0, 1.0, x.shape)
    v -= v.mean(axis=0)
    w = kinema.World(dt=0.01 if model == "impulse" else 2e-4)
    w.add(kinema.Box([0, 0, 0], [side] * 3))
    w.periodic = (True, True, True)
    if model == "impulse":
        w.set_collisions(restitution=1.0, event_driven=event_driven)
    else:
        w.set_collisions(model="spring_dashpot", stiffness=1e5, restitution=1.0)
    w.add_particles(x, velocity=v, mass=1.0, radius=d / 2)
    return w, side


def carnahan_starling(phi):
    return (1 + phi + phi**2 - phi**3) / (1 - phi) ** 3


def compressibility(tr, side):
    n = tr.positions.shape[1]
    kT = 2 * tr.kinetic[1:].mean() / (3 * n)
    p = np.trace(tr.pressure[1:], axis1=1, axis2=2) / 3
    return p.mean() * side**3 / (n * kT)


def test_the_kinetic_part_is_the_ideal_gas_law_exactly():
    # point particles never collide: p V = Σ m v ⊗ v, whose trace is 2 E_kin
    rng = np.random.default_rng(2)
    w = kinema.World(dt=0.01)
    w.add(kinema.Box([0, 0, 0], [2.0, 3.0, 4.0]))
    w.periodic = (True, True, True)
    w.add_particles(rng.uniform(0, 2, (100, 3)), velocity=rng.normal(0, 1, (100, 3)), mass=rng.uniform(1, 2, 100))
    tr = w.run(1.0, fps=10)
    assert np.isnan(tr.pressure[0]).all()  # no interval before the first frame
    volume = 24.0
    np.testing.assert_allclose(np.trace(tr.pressure[1:], axis1=1, axis2=2) * volume, 2 * tr.kinetic[1:], rtol=1e-12)
    expected = np.einsum("i,ij,ik->jk", w.masses, w.velocities, w.velocities) / volume
    np.testing.assert_allclose(tr.pressure[-1], expected, rtol=1e-12)
    assert tr.impacts.sum() == 0


@pytest.mark.parametrize("event_driven", [True, False])
def test_a_hard_sphere_gas_has_carnahan_and_starlings_pressure(event_driven):
    phi = 0.3
    w, side = periodic_gas(phi, 8, event_driven=event_driven)
    w.run(10.0, fps=1)  # from the lattice to equilibrium
    tr = w.run(40.0 if event_driven else 20.0, fps=2)
    z = compressibility(tr, side)
    assert z == pytest.approx(carnahan_starling(phi), rel=0.02)
    # the impacts of each frame add up to the run's, and the virial is isotropic
    assert tr.impacts[0] == 0 and tr.impacts.sum() > 10_000
    virial = tr.pressure[1:].mean(axis=0)
    assert np.abs(virial - np.trace(virial) / 3 * np.eye(3)).max() < 0.03 * np.trace(virial) / 3


def test_a_hard_disc_gas_has_hendersons_pressure_in_newtons_per_metre():
    # 2D: p A = N k T Z, Z = (1 + φ²/8) / (1 − φ)² (Henderson 1975), the pressure the trace
    # over x and y over 2, per unit length
    phi, n_side = 0.3, 24
    a = np.sqrt(np.pi / (4 * phi))  # square lattice of discs of diameter 1 m
    side = n_side * a
    g = (np.arange(n_side) + 0.5) * a
    xy = np.array(np.meshgrid(g, g, indexing="ij")).reshape(2, -1).T
    rng = np.random.default_rng(1)
    v = rng.normal(0.0, 1.0, (len(xy), 3))
    v[:, 2] = 0.0
    v -= v.mean(axis=0)
    w = kinema.World(dim=2, dt=0.01)
    w.add(kinema.Box([0, 0], [side, side]))
    w.periodic = (True, True)
    w.set_collisions(restitution=1.0, event_driven=True)
    w.add_particles(np.c_[xy, np.zeros(len(xy))], velocity=v, mass=1.0, radius=0.5)
    w.run(10.0, fps=1)
    tr = w.run(40.0, fps=2)
    n = len(xy)
    kT = tr.kinetic[1:].mean() / n  # two degrees of freedom
    p = np.trace(tr.pressure[1:, :2, :2], axis1=1, axis2=2) / 2
    assert np.all(tr.pressure[1:, 2, :] == 0) and np.all(tr.pressure[1:, :, 2] == 0)
    z = p.mean() * side * side / (n * kT)
    assert z == pytest.approx((1 + phi**2 / 8) / (1 - phi) ** 2, rel=0.02)


def test_the_spring_dashpot_model_books_its_contacts_dissipation_and_impacts():
    # a damped linear contact returns e u and dissipates ½ m* u² (1 − e²)
    k, m, e, u = 1e4, 1e-3, 0.5, 1.0
    w = kinema.World(dt=1e-6)
    w.set_collisions(model="spring_dashpot", stiffness=k, restitution=e)
    w.add_particles([[-0.0101, 0, 0], [0.0101, 0, 0]], velocity=[[u / 2, 0, 0], [-u / 2, 0, 0]], mass=m, radius=0.01)
    contacts = []
    for _ in range(30):
        w.step(100)
        contacts.append(w.collision_stats()["last"]["contacts"])
    total = w.collision_stats()["total"]
    assert total["impacts"] == 1 and max(contacts) == 1 and contacts[-1] == 0
    lost = 0.5 * (m / 2) * u * u * (1 - e * e)
    assert total["energy_lost"] == pytest.approx(lost, rel=2e-3)
    # and the books close: the kinetic energy the pair lost is what the dashpot took
    d = w.diagnostics()
    assert 0.5 * (m / 2) * u * u - d["kinetic"] == pytest.approx(total["energy_lost"], rel=2e-3)


def test_a_soft_sphere_gas_reports_its_pressure_through_the_forces_virial():
    # stiff elastic spring–dashpot spheres are nearly hard: their Z approaches the hard-sphere
    # gas's (within 5 % here at φ = 0.2, k = 1e5 N/m: the overlaps are 1 % of d)
    phi = 0.2
    w, side = periodic_gas(phi, 6, model="spring_dashpot")
    w.run(2.0, fps=5)
    tr = w.run(4.0, fps=10)
    assert tr.impacts.sum() > 1000
    assert compressibility(tr, side) == pytest.approx(carnahan_starling(phi), rel=0.05)


def test_pressure_needs_a_periodic_cell():
    w = kinema.World()
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.add_particles([0.5, 0.5, 0.5], velocity=[1, 0, 0], radius=0.1)
    assert w.run(0.1, fps=10).pressure is None  # walls: no volume the virial knows


def test_the_per_particle_stress_of_a_resting_stack_is_half_the_contact_force_times_the_distance():
    # Two spheres stacked on a floor, at rest under gravity (the force model): the upper one
    # rests on the lower with F = m g along z, at the distance of centres d = 2 r − δ, δ =
    # m g / k_n. Each gets ½ d m g in zz and nothing else (the floor's contact is a collider's,
    # left out); summed, Σ_pairs (x_i − x_j) ⊗ F = d m g.
    r, m, k, g = 0.01, 0.002, 1e4, 9.81
    w = kinema.World(dt=1e-5, method="verlet")
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.Gravity([0, 0, -g]))
    w.set_collisions(model="spring_dashpot", stiffness=k, restitution=0.2, friction=0.4)
    d_floor = 2 * m * g / k
    d_pair = m * g / k
    w.add_particles([[0, 0, r - d_floor], [0, 0, 3 * r - d_floor - d_pair]], mass=m, radius=r)
    w.step(20_000)
    s = w.particle_stress(kinetic=False)
    closed = 0.5 * (2 * r - d_pair) * m * g
    for p in (0, 1):
        assert s[p, 2, 2] == pytest.approx(closed, rel=1e-9)
        off = s[p].copy()
        off[2, 2] = 0.0
        assert np.abs(off).max() < 1e-12 * closed
    # the kinetic part: m v ⊗ v (at rest: nothing)
    np.testing.assert_allclose(w.particle_stress() - s, 0.0, atol=1e-20)
    # a moving particle alone: m v ⊗ v exactly
    free = kinema.World()
    free.add_particles([0, 0, 0], velocity=[1.0, 2.0, 0.0], mass=3.0)
    np.testing.assert_array_equal(free.particle_stress()[0], 3.0 * np.outer([1.0, 2.0, 0.0], [1.0, 2.0, 0.0]))
    # the impulse model has impulses, not forces
    imp = kinema.World()
    imp.add_particles([0, 0, 0], radius=0.1)
    imp.set_collisions()
    with pytest.raises(ValueError, match=r"model = 'impulse' is invalid: a per-particle stress needs contact forces"):
        imp.particle_stress()


def test_the_per_particle_stresses_sum_to_the_pressure_of_a_compressed_periodic_packing():
    # A periodic packing of soft spheres squeezed into a cell smaller than their lattice, at
    # rest: the pressure tensor of the trajectory (its virial over a frame / V, the kinetic
    # part ~0) is the per-particle stresses' sum / V.
    n_side, d, squeeze = 4, 1.0, 0.98
    side = n_side * d * squeeze
    g = (np.arange(n_side) + 0.5) * d * squeeze
    x = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    w = kinema.World(dt=1e-3, method="verlet")
    w.add(kinema.Box([0, 0, 0], [side] * 3))
    w.periodic = (True, True, True)
    w.set_collisions(model="spring_dashpot", stiffness=1e3, restitution=0.5)
    w.add_particles(x, mass=1.0, radius=d / 2)
    with pytest.warns(kinema.PlacementWarning):  # (squeezed on purpose)
        tr = w.run(0.2, fps=50)
    s = w.particle_stress()
    np.testing.assert_allclose(s.sum(axis=0) / side**3, tr.pressure[-1], rtol=1e-9, atol=1e-12 * np.abs(tr.pressure[-1]).max())
    # a simple cubic packing squeezed by 2 %: each of its 3 N contacts pushes k δ, δ = 0.02 d
    assert s.sum(axis=0)[0, 0] == pytest.approx(n_side**3 * 1e3 * 0.02 * d * (d - 0.02 * d), rel=1e-9)


@pytest.mark.parametrize("units", ["SI", "MD"])
def test_the_pressure_tensor_goes_into_h5md_and_back(tmp_path, units):
    # /observables/pressure: (F, 3, 3) in Pa (kJ mol-1 nm-3 in MD units), NaN at frame 0; read
    # back the same to rounding (the MD conversion's), and by h5py as written.
    import h5py

    w, side = periodic_gas(0.2, 4, model="spring_dashpot")
    tr = w.run(0.05, fps=200)
    path = tr.save(tmp_path / "gas.h5", units=units)
    with h5py.File(path, "r") as f:
        ds = f["observables/pressure/value"]
        assert ds.shape == tr.pressure.shape
        assert ds.attrs["unit"] == ("Pa" if units == "SI" else "kJ mol-1 nm-3")
    back = kinema.load_trajectory(path)
    np.testing.assert_allclose(back.pressure, tr.pressure, rtol=1e-12, equal_nan=True)
    assert np.isnan(back.pressure[0]).all() and np.isfinite(back.pressure[1:]).all()
    # a 2D world's: N m-1
    flat = kinema.World(dim=2, dt=1e-3)
    flat.add(kinema.Box([0, 0], [4, 4]))
    flat.periodic = (True, True)
    flat.set_collisions(restitution=1.0)
    flat.add_particles([[1, 1, 0], [3, 3, 0]], velocity=[[1, 0.5, 0], [-1, 0.2, 0]], radius=0.2)
    tr2 = flat.run(0.02, fps=100)
    p2 = tr2.save(tmp_path / "flat.h5")
    with h5py.File(p2, "r") as f:
        assert f["observables/pressure/value"].attrs["unit"] == "N m-1"
    np.testing.assert_allclose(kinema.load_trajectory(p2).pressure, tr2.pressure, rtol=0, equal_nan=True)
