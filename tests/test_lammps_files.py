"""Files LAMMPS itself writes, read by kinema: a tiny LAMMPS run (``lmp``, Debian's package,
which ``make test`` installs) in the units real, metal and si, atom styles atomic and sphere,
writes a ``dump custom`` (``dump_modify units yes time yes``, 15 digits), a plain ``dump
atom`` (scaled coordinates, ``%g``) and a ``write_data`` file; kinema reads each and is
compared with the numbers LAMMPS wrote × LAMMPS's unit factors, and with LAMMPS's own sums
(``fix print`` of the total mass, the centre of mass and the kinetic energy). Skipped where
``lmp`` is not installed."""

import math
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError

LMP = shutil.which("lmp")
pytestmark = pytest.mark.skipif(LMP is None, reason="LAMMPS (lmp) is not installed: apt-get install lammps (make test installs it)")

# LAMMPS's units in SI, by LAMMPS's own constants (src/update.cpp, Update::set_units): a gram
# per mole is 1e-3 kg / 6.02214129e23; a kcal/mol 4184 J / 6.02214129e23, an eV 1.602176565e-19
# J (LAMMPS's qelectron); the velocity unit is the length per the time unit
AVOGADRO = 6.02214129e23
UNITS = {  # length m, time s, mass kg, energy J
    "real": (1e-10, 1e-15, 1e-3 / AVOGADRO, 4184.0 / AVOGADRO),
    "metal": (1e-10, 1e-12, 1e-3 / AVOGADRO, 1.602176565e-19),
    "si": (1.0, 1.0, 1.0, 1.0),
}
# each run in its style's units: the box edge, the timestep, the two types' masses (atomic)
# or diameters and densities (sphere), and the temperature (K) of velocity create
RUNS = {
    "real": {"box": 20.0, "dt": 2.0, "masses": (39.948, 4.0026), "diameters": (3.4, 2.6), "densities": (1.5, 0.8)},
    "metal": {"box": 20.0, "dt": 0.002, "masses": (39.948, 4.0026), "diameters": (3.4, 2.6), "densities": (1.5, 0.8)},
    "si": {"box": 2e-9, "dt": 1e-15, "masses": (6.6335209e-26, 6.6464731e-27), "diameters": (3.4e-10, 2.6e-10), "densities": (1500.0, 800.0)},
}
CASES = [("real", "atomic"), ("metal", "sphere"), ("si", "atomic"), ("si", "sphere")]
STEPS, EVERY = 10, 5  # frames at steps 0, 5, 10


def script(units, style):
    """The LAMMPS input: 24 + 12 atoms of two types placed at random inside a box periodic in x
    and y (fixed walls in z), no forces (pair zero), velocities from ``velocity create`` at
    300 K, ``fix nve`` for 10 steps; the three files and LAMMPS's sums every 5 steps."""
    r = RUNS[units]
    box, inner = r["box"], (0.1 * r["box"], 0.9 * r["box"])
    if style == "atomic":
        per_type = [f"mass {t} {m!r}" for t, m in ((1, r["masses"][0]), (2, r["masses"][1]))]
    else:  # (LAMMPS computes each mass as density × 4π/3 r³)
        per_type = [f"set type {t} diameter {d!r}\nset type {t} density {rho!r}" for t, d, rho in zip((1, 2), r["diameters"], r["densities"], strict=True)]
    sums = " ".join(f"$({q}:%.17g)" for q in ("time", "ke", "mass(all)", "xcm(all,x)", "xcm(all,y)", "xcm(all,z)"))
    radius = " radius" if style == "sphere" else ""
    return "\n".join(
        [
            f"units {units}",
            f"atom_style {style}",
            "boundary p p f",
            f"region box block 0 {box!r} 0 {box!r} 0 {box!r}",
            f"region inner block {inner[0]!r} {inner[1]!r} {inner[0]!r} {inner[1]!r} {inner[0]!r} {inner[1]!r}",
            "create_box 2 box",
            "create_atoms 1 random 24 12345 inner",
            "create_atoms 2 random 12 54321 inner",
            *per_type,
            f"pair_style zero {0.25 * box!r}",
            "pair_coeff * *",
            f"neighbor {0.05 * box!r} bin",
            "velocity all create 300.0 4928459 dist gaussian",
            f"timestep {r['dt']!r}",
            "fix 1 all nve",
            f'fix sums all print {EVERY} "$(step) {sums}" file sums.txt screen no',
            f"dump custom all custom {EVERY} custom.lammpstrj id type x y z vx vy vz mass{radius}",
            "dump_modify custom units yes time yes format float %20.15g",
            f"dump atom all atom {EVERY} atom.lammpstrj",
            f"run {STEPS}",
            "write_data out.data",
        ]
    )


@pytest.fixture(scope="module", params=CASES, ids=[f"{u}-{s}" for u, s in CASES])
def run(request, tmp_path_factory):
    """The folder where LAMMPS wrote its files, the units and the atom style."""
    units, style = request.param
    folder = tmp_path_factory.mktemp(f"lammps_{units}_{style}")
    (folder / "in.test").write_text(script(units, style) + "\n")
    done = subprocess.run([LMP, "-in", "in.test", "-log", "none", "-screen", "none"], cwd=folder, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    return folder, units, style


def dump_frames(path):
    """LAMMPS's dump as it wrote it, parsed here: per frame the step and a dict column name →
    values (float of each decimal), rows in the file's order."""
    lines = path.read_text().splitlines()
    frames, i = [], 0
    while i < len(lines):
        if lines[i] == "ITEM: TIMESTEP":
            step = int(lines[i + 1])
        elif lines[i] == "ITEM: NUMBER OF ATOMS":
            n = int(lines[i + 1])
        elif lines[i].startswith("ITEM: ATOMS "):
            names = lines[i].split()[2:]
            rows = np.array([[float(w) for w in line.split()] for line in lines[i + 1 : i + 1 + n]])
            frames.append((step, dict(zip(names, rows.T, strict=True))))
            i += n
        i += 1
    return frames


def load(path, **options):
    """``Trajectory.load`` with warnings turned into errors: a reader that warns fails here."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return kinema.Trajectory.load(path, **options)


def columns(back, ids):
    """The columns of ``back`` of the particles of LAMMPS ids ``ids``, in that order (kinema's
    ids are LAMMPS's − 1: from 0)."""
    return np.searchsorted(back.ids, ids.astype(np.int64) - 1)


def test_a_dump_custom_lammps_wrote_reads_as_lammps_wrote_it(run):
    folder, units, style = run
    length, time, mass, energy = UNITS[units]
    velocity = length / time
    back = load(folder / "custom.lammpstrj")  # ITEM: UNITS says them
    written = dump_frames(folder / "custom.lammpstrj")
    assert [step for step, _ in written] == [0, 5, 10] and back.source.step.tolist() == [0, 5, 10]
    np.testing.assert_allclose(back.t, np.array([0, 5, 10]) * RUNS[units]["dt"] * time, rtol=1e-15)  # step × dt, ITEM: TIME
    assert back.periodic == (True, True, False)
    np.testing.assert_allclose(back.box_edges, [RUNS[units]["box"] * length] * 3, rtol=1e-15)
    for k, (_, c) in enumerate(written):
        col = columns(back, c["id"])
        np.testing.assert_array_equal(back.ids[col], c["id"].astype(np.int64) - 1)
        assert back.species[col].tolist() == [str(int(t)) for t in c["type"]]
        x = np.stack([c["x"], c["y"], c["z"]], axis=1)
        v = np.stack([c["vx"], c["vy"], c["vz"]], axis=1)
        np.testing.assert_allclose(back.positions[k][col], x * length, rtol=1e-15, atol=0)
        np.testing.assert_allclose(back.velocities[k][col], v * velocity, rtol=1e-15, atol=0)
        np.testing.assert_allclose(back.masses[col], c["mass"] * mass, rtol=1e-15, atol=0)
        if style == "sphere":
            np.testing.assert_allclose(back.radii[col], c["radius"] * length, rtol=1e-15, atol=0)
    # LAMMPS's own sums (fix print, 17 digits): the total mass, the centre of mass and the
    # kinetic energy in the style's energy unit (its mvv2e: 8 to 10 digits, so within 1e-7)
    sums = np.loadtxt(folder / "sums.txt", ndmin=2)
    np.testing.assert_array_equal(sums[:, 0], [0, 5, 10])
    m = back.masses
    for k, (_, t, ke, total, *centre) in enumerate(sums):
        assert back.t[k] == pytest.approx(t * time, rel=1e-15)
        assert m.sum() == pytest.approx(total * mass, rel=1e-13)
        np.testing.assert_allclose(m @ back.positions[k] / m.sum(), np.array(centre) * length, rtol=1e-13)
        assert 0.5 * np.sum(m[:, None] * back.velocities[k] ** 2) == pytest.approx(ke * energy, rel=1e-7)


def test_a_plain_dump_atom_reads_within_its_six_digits(run):
    folder, units, style = run
    length = UNITS[units][0]
    with pytest.raises(TrajectoryFileError, match=r"atom\.lammpstrj: a LAMMPS file that does not say its units"):
        load(folder / "atom.lammpstrj")  # no ITEM: UNITS in this dump
    back = load(folder / "atom.lammpstrj", units=units)
    custom = dump_frames(folder / "custom.lammpstrj")
    assert back.source.step.tolist() == [0, 5, 10] and back.t.tolist() == [0.0, 1.0, 2.0]  # no ITEM: TIME: the frame index
    assert np.isnan(back.velocities).all() and back.masses is None and back.periodic == (True, True, False)  # (unknown: NaN)
    edge = RUNS[units]["box"] * length
    for k, (_, c) in enumerate(custom):
        col = columns(back, c["id"])
        x = np.stack([c["x"], c["y"], c["z"]], axis=1) * length
        # xs ys zs as %g, 6 significant digits of a fraction of the box (0.1 to 0.9 here): within half a unit of the 6th digit of the edge
        assert np.max(np.abs(back.positions[k][col] - x)) <= 5.01e-7 * edge


def test_write_data_reads_as_lammps_wrote_it(run):
    folder, units, style = run
    length, time, mass, _ = UNITS[units]
    last = dump_frames(folder / "custom.lammpstrj")[-1][1]  # step 10, when write_data wrote
    order = np.argsort(last["id"])
    x = np.stack([last["x"], last["y"], last["z"]], axis=1)[order] * length
    v = np.stack([last["vx"], last["vy"], last["vz"]], axis=1)[order] * length / time
    back = load(folder / "out.data", units=units)  # LAMMPS 2021's write_data names no units
    np.testing.assert_array_equal(back.ids, np.sort(last["id"]).astype(np.int64) - 1)
    assert back.source.step.tolist() == [STEPS]  # the title's timestep = 10
    # write_data's 17 digits against the dump's 15
    np.testing.assert_allclose(back.positions[0], x, rtol=1e-14, atol=0)
    np.testing.assert_allclose(back.velocities[0], v, rtol=1e-14, atol=0)
    np.testing.assert_allclose(back.masses, last["mass"][order] * mass, rtol=1e-14)  # sphere: density × 4π/3 r³, as LAMMPS
    if style == "sphere":
        np.testing.assert_allclose(back.radii, last["radius"][order] * length, rtol=1e-14)
    np.testing.assert_allclose(back.box_edges, [RUNS[units]["box"] * length] * 3, rtol=1e-15)
    assert back.periodic == (True, True, True)  # a data file does not say its boundaries: LAMMPS's default, p p p
    w = kinema.World(dt=1e-15)
    w.add_particles_from(folder / "out.data", units=units)
    np.testing.assert_array_equal(w.positions, back.positions[0])
    np.testing.assert_array_equal(w.velocities, back.velocities[0])
    np.testing.assert_array_equal(w.masses, back.masses)
    assert math.isclose(float(w.masses.sum()), float(np.sum(last["mass"]) * mass), rel_tol=1e-13)
