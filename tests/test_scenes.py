"""Scene files: every example loads and runs, a scene round-trips, and a bad scene gets one
clear line per problem naming the file, the key path, the value and what is allowed."""

import re
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.scene import Scene, SceneError

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
EXAMPLES = sorted(p.name for p in SCENES.glob("*.toml"))


def load(name):
    return kinema.load_scene(SCENES / name)


def test_every_example_is_listed():
    for name in (
        "bouncing_balls",
        "newtons_cradle",
        "billiards_2d",
        "sand_box",
        "cloth_on_sphere",
        "maxwell_gas",
        "kepler_euler",
        "kepler_rk4",
        "kepler_verlet",
        "demo",
        "fountain",
        "pour",
    ):
        assert f"{name}.toml" in EXAMPLES


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_loads_and_runs_shortened(name):
    w = load(name)
    assert isinstance(w.scene, Scene) and (len(w) > 0 or w.scene.emitters)
    traj = w.run(min(0.1, w.scene.world.duration), fps=w.scene.world.fps)
    assert traj.alive[-1].any() and np.all(np.isfinite(traj.positions[traj.alive]))


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
# (the demo's heap at 60 Hz overlaps by up to 10 % of r mid-fall, which a world read from it
# is told of as a placement)
@pytest.mark.filterwarnings("ignore::kinema.PlacementWarning")
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_round_trips_to_an_identical_world(name, tmp_path):
    w = load(name)
    w.step(5)
    path = w.to_scene().to_toml(tmp_path / "again.toml")
    w2 = kinema.load_scene(path)
    assert (w2.dim, w2.dt, w2.method) == (w.dim, w.dt, w.method)
    for a in ("positions", "velocities", "masses"):
        np.testing.assert_array_equal(getattr(w2, a), getattr(w, a))
    np.testing.assert_array_equal(w2._core.radii, w._core.radii)
    np.testing.assert_array_equal(w2._core.inverse_masses, w._core.inverse_masses)
    assert w2.collisions == w.collisions and w2.periodic == w.periodic
    assert [type(c) for c in w2.colliders] == [type(c) for c in w.colliders]
    assert [type(f) for f in w2.forces] == [type(f) for f in w.forces]
    assert w2.to_scene().to_dict() == w.to_scene().to_dict()
    assert w2.scene.world == w.scene.world and w2.scene.render == w.scene.render and w2.scene.output == w.scene.output
    # the same state, forces and settings step alike (not bit for bit: the scene does not hold
    # the time or the method's caches, such as Verlet's stored acceleration); an emitter starts
    # again from its first particle in the loaded world (no time), so only emitter-free scenes
    if w.scene.emitters:
        return
    acted = (w.collision_stats() or {"total": {"impulses": 0}})["total"]["impulses"]
    w.step(5)
    w2.step(5)
    if w.collision_stats() and w.collision_stats()["total"]["impulses"] > acted:
        # contacts acted in these steps (the demo's heap at 60 Hz touches from its first step):
        # their warm start and which of them rested are caches a scene does not hold either,
        # and a pile's impacts amplify what they decide; a world read again steps as another
        # read of the same file does, bit for bit
        w3 = kinema.load_scene(path)
        w3.step(5)
        np.testing.assert_array_equal(w3.positions, w2.positions)
    else:
        np.testing.assert_allclose(w2.positions, w.positions, rtol=1e-9, atol=1e-9)


def test_maxwell_gas_conserves_momentum_and_energy():
    w = load("maxwell_gas.toml")
    assert all(w.periodic)
    traj = w.run(0.3, fps=30)
    assert np.abs(traj.momentum).max() < 1e-10  # zero_momentum = true, elastic impulses
    assert abs(traj.total[-1] - traj.total[0]) < 1e-9 * traj.total[0]
    assert traj.collision_energy_lost[-1] < 1e-9 * traj.total[0]


def test_newtons_cradle_passes_the_velocity_along():
    w = load("newtons_cradle.toml")
    balls = slice(5, 10)
    # the raised ball reaches the row after a quarter period (about 0.5 s)
    w.run(0.75, fps=50)
    speed = np.linalg.norm(w.velocities[balls], axis=1)
    assert speed[4] > 5 * speed[0] and speed[4] > 1.0
    assert np.all(speed[1:4] < 0.3 * speed[4])


def test_bouncing_balls_rebound_with_their_own_restitution():
    w = load("bouncing_balls.toml")
    e = np.linspace(0.1, 0.9, 9)
    w.run(0.5, fps=100)  # every ball has bounced once (falls 0.95 m in 0.44 s)
    impact = np.sqrt(2 * 9.81 * 0.95)
    vz = w.velocities[:, 2]
    np.testing.assert_allclose(vz - vz[0], (e - e[0]) * impact, atol=0.05 * impact)


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
def test_kepler_scenes_differ_only_by_method():
    radius = {}
    for m in ("euler", "rk4", "verlet"):
        w = load(f"kepler_{m}.toml")
        assert w.method == m
        w.run(2 * np.pi, fps=20)
        radius[m] = np.linalg.norm(w.positions[0])
    assert radius["euler"] > 1.5  # forward Euler spirals out
    assert abs(radius["verlet"] - 1) < 0.02 and abs(radius["rk4"] - 1) < 0.02


def test_cloth_rests_on_the_sphere_not_in_it():
    w = load("cloth_on_sphere.toml")
    assert len(w.forces[1].i) == 2 * 19 * 20 + 2 * 19 * 19  # stretch + shear springs of the grid rule
    w.run(0.6, fps=30)
    d = np.linalg.norm(w.positions - [0, 0, 0.5], axis=1)
    assert d.min() > 0.3 - 1e-6
    assert np.all(np.isfinite(w.positions))


def test_random_block_keeps_min_distance_and_is_seeded():
    w = load("sand_box.toml")
    x = w.positions[:300]
    d = np.linalg.norm(x[:, None] - x[None], axis=2) + np.eye(len(x))
    assert d.min() >= 0.021
    np.testing.assert_array_equal(load("sand_box.toml").positions, w.positions)
    assert 0.0045 <= w.masses.min() and w.masses.max() <= 0.0055


def test_billiard_balls_stay_on_the_table():
    w = load("billiards_2d.toml")
    w.run(1.0, fps=30)
    x = w.positions
    assert np.all(x[:, :2] >= 0.028575 - 1e-9) and np.all(x[:, 0] <= 2.54) and np.all(x[:, 2] == 0)


def test_to_scene_of_a_world_made_in_code(tmp_path):
    w = kinema.World(dt=0.01, method="rk4")
    w.add_particles([[0, 0, 0], [0, 0, -1.0]], mass=[1.0, 0.5], pinned=[True, False], radius=0.1)
    w.add(kinema.Gravity())
    w.add(kinema.Spring(0, 1, k=100.0, rest_length=1.0, damping=0.5))
    w.add(kinema.Plane([0, 0, -3], [0, 0, 1], restitution=0.5))
    assert w.scene is None
    w2 = kinema.load_scene(w.to_scene().to_toml(tmp_path / "s.toml"))
    w.step(50)
    w2.step(50)
    np.testing.assert_allclose(w2.positions, w.positions, rtol=1e-12, atol=1e-12)


def test_python_force_cannot_be_written():
    w = kinema.World()
    w.add_particles([0, 0, 0])
    w.add(kinema.PythonForce(lambda t, x, v: -x))
    with pytest.raises(ValueError, match="PythonForce cannot be written"):
        w.to_scene()


# -- errors -----------------------------------------------------------------------------------

BAD = """
[world]
dt = 0.001
method = "verlett"
duraton = 2

[[particles]]
type = "lattice"
counts = [3, 3]
spacing = -0.1

[[forces]]
type = "gravity"

[[forces]]
type = "drag"

[[forces]]
type = "spring"
i = [0]
j = [1]
k = -5

[[forces]]
type = "magnet"
"""


def errors_of(text, tmp_path, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        kinema.load_scene(path)
    return str(info.value).splitlines(), str(path)


def test_each_problem_is_one_line_naming_file_key_value_and_what_is_allowed(tmp_path):
    lines, path = errors_of(BAD, tmp_path)
    assert len(lines) == 5, lines
    assert all(line.startswith(f"{path}: ") for line in lines)
    assert f"{path}: world.method: 'verlett' is invalid: unknown method; did you mean 'verlet'? valid methods are: euler" in lines[0]
    assert "world.duraton: unknown key; did you mean 'duration'?" in lines[1]
    assert "particles[0].spacing: -0.1 is invalid: input should be greater than 0" in lines[2]
    assert lines[3] == f"{path}: forces[2].k: -5 is invalid: input should be greater than 0"
    assert "forces[3]: {'type': 'magnet'} is invalid: type must be one of 'gravity', 'drag', 'spring'" in lines[4]


def test_unknown_keys_are_errors_everywhere(tmp_path):
    lines, _ = errors_of('[render]\ncolour_by = "id"\n[extra]\na = 1\n[[colliders]]\ntype = "plane"\npoint = [0,0,0]\nnormal = [0,0,1]\nbounce = 1\n', tmp_path)
    assert any("render.colour_by: unknown key; did you mean 'color_by'?" in line for line in lines)
    assert any("extra: unknown key" in line for line in lines)
    assert any("colliders[0].bounce: unknown key" in line and "restitution" in line for line in lines)


def test_missing_values_and_ranges(tmp_path):
    lines, _ = errors_of('[[colliders]]\ntype = "sphere"\ncenter = [0,0,0]\nradius = -1\n[collisions]\nrestitution = 1.5\n', tmp_path)
    assert any("colliders[0].radius: -1 is invalid: input should be greater than or equal to 0" in line for line in lines)
    assert any("collisions.restitution: 1.5 is invalid: input should be less than or equal to 1" in line for line in lines)
    lines, _ = errors_of('[[forces]]\ntype = "spring"\ni = [0]\nj = [1]\n', tmp_path)
    assert lines == [f"{tmp_path / 'bad.toml'}: forces[0].k: missing: a value is required"]


def test_toml_syntax_error_names_line_and_column(tmp_path):
    lines, path = errors_of("[world]\ndt = 0.001\nmethod = verlet\n", tmp_path)
    assert len(lines) == 1 and lines[0].startswith(f"{path}: TOML syntax error") and "line 3" in lines[0] and "column" in lines[0]


def test_missing_file_and_directory_are_one_line(tmp_path):
    with pytest.raises(SceneError, match=r"nope.toml: no such file$"):
        kinema.load_scene(tmp_path / "nope.toml")
    with pytest.raises(SceneError, match="is a directory"):
        kinema.load_scene(tmp_path)


def test_engine_refusals_name_the_entry(tmp_path):
    lines, _ = errors_of('[world]\ndim = 2\n[[particles]]\ntype = "list"\npositions = [[0, 0, 1]]\n', tmp_path)
    assert len(lines) == 1 and "particles[0]:" in lines[0] and "z" in lines[0]
    lines, _ = errors_of('[[particles]]\ntype = "list"\npositions = [[0,0,0],[1,0,0]]\n[[forces]]\ntype = "spring"\ni = [0]\nj = [5]\nk = 1.0\n', tmp_path)
    assert lines == [f"{tmp_path / 'bad.toml'}: forces[0]: spring 0 joins particles 0 and 5, but the scene has 2 particles (indices 0..1)"]
    lines, _ = errors_of('[[particles]]\ntype = "list"\npositions = [[0,0,0],[1,0,0]]\nmass = [1.0, 2.0, 3.0]\n', tmp_path)
    assert lines == [f"{tmp_path / 'bad.toml'}: particles[0]: mass has 3 values for 2 particles"]


def test_spring_rules_are_checked(tmp_path):
    lines, _ = errors_of(
        '[[particles]]\ntype = "list"\npositions = [[0,0,0],[1,0,0]]\n[[forces]]\ntype = "spring"\nrule = "grid"\nblock = 0\nk = 1.0\n', tmp_path
    )
    assert "rule = 'grid' needs a lattice block" in lines[0]
    lines, _ = errors_of('[[forces]]\ntype = "spring"\nrule = "chain"\nblock = 3\nk = 1.0\n', tmp_path)
    assert "block = 3" in lines[0]


def test_chain_rule_and_maxwell_velocities(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        '[[particles]]\ntype = "lattice"\ncounts = [5, 1, 1]\nspacing = 0.5\nmass = 2.0\nvelocity = { kT = 8.0, seed = 3, zero_momentum = true }\n'
        '[[forces]]\ntype = "spring"\nrule = "chain"\nblock = 0\nk = 10.0\n'
    )
    w = kinema.load_scene(path)
    np.testing.assert_array_equal(w.forces[0].i, [0, 1, 2, 3])
    np.testing.assert_allclose(w.forces[0].rest_length, 0.5)
    np.testing.assert_allclose(w.momenta.sum(axis=0), 0, atol=1e-12)
    np.testing.assert_array_equal(kinema.load_scene(path).velocities, w.velocities)  # seeded


def test_isotropic_velocities_have_one_speed_and_random_directions(tmp_path):
    path = tmp_path / "s.toml"
    block = '[[particles]]\ntype = "random"\nlo = [0, 0, 0]\nhi = [1, 1, 1]\ncount = 4000\nseed = 2\nvelocity = { speed = 3.0 }\n'
    path.write_text(block)
    v = kinema.load_scene(path).velocities
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 3.0, rtol=1e-14)
    # uniform on the sphere: each component of the direction is uniform on [-1, 1]
    # (Archimedes' hat-box theorem), mean 0 and variance 1/3
    u = v / 3.0
    assert np.abs(u.mean(axis=0)).max() < 4 / np.sqrt(3 * 4000)
    np.testing.assert_allclose((u**2).mean(axis=0), 1 / 3, atol=0.02)
    np.testing.assert_array_equal(kinema.load_scene(path).velocities, v)  # seeded
    path.write_text("[world]\ndim = 2\n" + block.replace("count = 4000", "count = 50").replace("hi = [1, 1, 1]", "hi = [1, 1, 0]"))
    v2 = kinema.load_scene(path).velocities
    assert np.all(v2[:, 2] == 0) and np.allclose(np.linalg.norm(v2, axis=1), 3.0)
    lines, _ = errors_of(block.replace("speed = 3.0", "speed = -1.0"), tmp_path)
    assert "velocity.speed" in lines[0] and "-1" in lines[0]


# -- strict values: no coercion, bounds that keep the engine's numbers finite -----------------

ONE = '[[particles]]\ntype = "list"\npositions = [[0, 0, 0]]\n'


def test_strings_and_booleans_are_not_numbers(tmp_path):
    lines, path = errors_of('[world]\ndt = "1e-3"\n[[particles]]\ntype = "list"\npositions = [["0", true, "1e3"]]\nmass = "2"\n', tmp_path)
    assert lines == [
        f"{path}: world.dt: '1e-3' is invalid: input should be a valid number",
        f"{path}: particles[0].mass: '2' is invalid: input should be a valid number",
        f"{path}: particles[0].positions[0][0]: '0' is invalid: input should be a valid number",
        f"{path}: particles[0].positions[0][1]: True is invalid: input should be a valid number",
        f"{path}: particles[0].positions[0][2]: '1e3' is invalid: input should be a valid number",
    ]


def test_floats_are_not_integers_and_numbers_are_not_booleans(tmp_path):
    text = '[world]\ndim = 2.0\n[[particles]]\ntype = "random"\nlo = [0, 0]\nhi = [1, 1]\ncount = 3.0\npinned = 1\n[output]\nvideo = 0\n'
    lines, path = errors_of(text, tmp_path)
    assert f"{path}: world.dim: 2.0 is invalid: input should be 2 or 3" in lines
    assert f"{path}: particles[0].count: 3.0 is invalid: input should be a valid integer" in lines
    assert f"{path}: particles[0].pinned: 1 is invalid: input should be a valid boolean" in lines
    assert f"{path}: output.video: 0 is invalid: input should be 'mp4' or 'gif' or False" in lines
    assert len(lines) == 4, lines


def test_integers_are_taken_where_floats_are_wanted(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[world]\ndim = 2\ndt = 1\nduration = 2\nfps = 1\n[[particles]]\ntype = "list"\npositions = [[1, 2]]\nmass = 3\nradius = 0\n')
    w = kinema.load_scene(path)
    assert (w.dim, w.dt, w.scene.world.duration) == (2, 1.0, 2.0) and isinstance(w.scene.world.dt, float)
    np.testing.assert_array_equal(w.positions, [[1, 2, 0]])
    assert w.masses.tolist() == [3.0]


@pytest.mark.parametrize(
    ("line", "shown", "allowed"),
    [
        ("dt = 1e-320", "1e-320", "finite number of seconds >= 1e-300"),
        ("dt = inf", "inf", "finite number of seconds >= 1e-300"),
        ("dt = nan", "nan", "finite number of seconds >= 1e-300"),
        ("duration = inf", "inf", "finite number of seconds >= 0"),
        ("fps = 1e-9", "1e-09", "finite number >= 1e-06"),
    ],
)
def test_world_numbers_must_be_finite_and_in_range(tmp_path, line, shown, allowed):
    lines, path = errors_of(f"[world]\n{line}\n", tmp_path)
    key = line.split(" = ")[0]
    assert len(lines) == 1 and lines[0].startswith(f"{path}: world.{key}: {shown} is invalid: ") and allowed in lines[0], lines


def test_indices_and_counts_must_fit(tmp_path):
    spring = '[[forces]]\ntype = "spring"\ni = [0]\nj = [1000000000000000000000000000000]\nk = 1.0\n'
    lines, path = errors_of(ONE + spring, tmp_path)
    assert lines == [f"{path}: forces[0].j[0]: 1000000000000000000000000000000 is invalid: input should be less than 4294967295"]
    lines, _ = errors_of(ONE + spring.replace("1000000000000000000000000000000", "1e30"), tmp_path)
    assert lines == [f"{path}: forces[0].j[0]: 1e+30 is invalid: input should be a valid integer"]
    lines, _ = errors_of('[[particles]]\ntype = "lattice"\ncounts = [100000, 100000, 100000]\n', tmp_path)
    assert lines == [
        f"{path}: particles[0].counts: [100000, 100000, 100000] is invalid: the lattice would have 1,000,000,000,000,000 particles, more than 4,294,967,295"
    ]
    lines, _ = errors_of(ONE.replace('"list"', '"random"').replace("positions = [[0, 0, 0]]", "lo = [0, 0]\nhi = [1, 1]\ncount = 10000000000"), tmp_path)
    assert lines == [f"{path}: particles[0].count: 10000000000 is invalid: input should be less than or equal to 4294967295"]
    lines, _ = errors_of(ONE + "seed = -1\n", tmp_path)
    assert lines == [f"{path}: particles[0].seed: -1 is invalid: input should be greater than or equal to 0"]


def test_video_fps_must_be_playable(tmp_path):
    lines, path = errors_of("[render]\nfps = 1e-300\n", tmp_path)
    assert lines == [f"{path}: render.fps: 1e-300 is invalid: input should be greater than or equal to 0.01"]


CAMERA_ERRORS = [
    # (world.dim, camera table, the line after "<file>: ")
    (2, '{ type = "3d", eye = [0, -5, 2], target = [0, 0, 0] }', "render.camera.type: '3d' is invalid: a 2D world (world.dim = 2) needs a '2d' camera"),
    (3, '{ type = "2d", xmin = 0, ymin = 0, xmax = 2, ymax = 1 }', "render.camera.type: '2d' is invalid: a 3D world (world.dim = 3) needs a '3d' camera"),
    (2, "{ xmin = 0, ymin = 0, xmax = 2, ymax = 1 }", "is invalid: type must be one of '2d', '3d'"),
    (2, '{ type = "2d", xmin = 2, ymin = 0, xmax = 0, ymax = 1 }', "the view must be a finite rectangle with xmin < xmax and ymin < ymax (m)"),
    (2, '{ type = "2d", xmin = 0, ymin = 1, xmax = 2, ymax = 1 }', "the view must be a finite rectangle with xmin < xmax and ymin < ymax (m)"),
    (2, '{ type = "2d", xmin = nan, ymin = 0, xmax = 2, ymax = 1 }', "the view must be a finite rectangle"),
    (2, '{ type = "2d", xmin = -1e308, ymin = 0, xmax = 1e308, ymax = 1 }', "a finite rectangle with hi > lo on both axes"),  # the width is beyond float64
    (3, '{ type = "3d", eye = [0, 0, 1], target = [0, 0, 1] }', "target = [0.0, 0.0, 1.0] is invalid: a finite point different from eye"),
    (3, '{ type = "3d", eye = [0, 0, 5], target = [0, 0, 0] }', "up = [0.0, 0.0, 1.0] is invalid: a finite direction not parallel to target - eye"),
    (3, '{ type = "3d", eye = [0, -5, 2], target = [0, 0, 0], up = [0, 0, 0] }', "up = [0.0, 0.0, 0.0] is invalid: a finite direction"),
    (3, '{ type = "3d", eye = [0, -5, inf], target = [0, 0, 0] }', "eye = [0.0, -5.0, inf]: the camera's eye must be finite"),
    (3, '{ type = "3d", eye = [0, -5], target = [0, 0, 0] }', "render.camera.eye: [0, -5] is invalid: list should have at least 3 items"),
    (3, '{ type = "3d", eye = [0, -5, 2], target = [0, 0, 0], fov_deg = 180 }', "render.camera.fov_deg: 180 is invalid: input should be less than 180"),
]


@pytest.mark.parametrize(("dim", "camera", "expected"), CAMERA_ERRORS)
def test_a_camera_is_checked_when_the_scene_is_read(tmp_path, dim, camera, expected):
    # Each was found only after the whole run, when the video was rendered (exit 2 with the
    # engine's message and no file name; the trajectory lost with the staging folder).
    lines, path = errors_of(f"[world]\ndim = {dim}\n[render]\ncamera = {camera}\n", tmp_path)
    assert len(lines) == 1 and lines[0].startswith(f"{path}: ") and expected in lines[0], lines


def test_a_spring_naming_a_missing_block_is_one_line_naming_the_keys(tmp_path):
    lines, path = errors_of('[[forces]]\ntype = "spring"\nrule = "chain"\nblock = 3\nk = 1.0\n', tmp_path)
    assert lines == [f"{path}: a spring names block = 3, but the scene has 0 [[particles]] blocks"]


def _docs_block(after: str, lang: str) -> str:
    """The first ```lang block of docs/scenes.md after the text ``after``."""
    text = (Path(__file__).resolve().parent.parent / "docs" / "scenes.md").read_text()
    fence = re.compile(f"```{lang}( [^\n]*)?\n")  # (the fence line may carry test_docs.py's options)
    block = text[fence.search(text, text.index(after)).end() :]
    return block[: block.index("```")]


def _docs_camera_scene() -> str:
    return _docs_block("An example, `camera.toml`", "toml")


def test_the_camera_example_of_the_docs_runs_in_python(tmp_path, monkeypatch):
    from PIL import Image

    monkeypatch.chdir(tmp_path)
    (tmp_path / "camera.toml").write_text(_docs_camera_scene())
    exec(compile(_docs_block("`kinema run camera.toml` writes", "python"), "docs/scenes.md", "exec"), {})
    with Image.open(tmp_path / "camera_t0.png") as im:
        assert im.size == (640, 360)


def test_the_camera_example_of_the_docs_films_its_scene(tmp_path):
    # docs/scenes.md's camera.toml: three balls at z = 1 m seen from y = -3 m, 1.2 m up,
    # looking at (0, 0, 0.5) with a 30 degree field of view.
    import imageio_ffmpeg
    from typer.testing import CliRunner

    from kinema.cli import app

    (tmp_path / "camera.toml").write_text(_docs_camera_scene())
    scene = Scene.from_toml(tmp_path / "camera.toml")
    assert scene.render.camera.type == "3d" and scene.render.camera.fov_deg == 30
    res = CliRunner().invoke(app, ["run", str(tmp_path / "camera.toml"), "-o", str(tmp_path / "out"), "--duration", "0.5"])
    assert res.exit_code == 0, res.output
    reader = imageio_ffmpeg.read_frames(str(tmp_path / "out" / "camera.mp4"))
    meta = next(reader)
    w, h = meta["size"]
    assert (w, h, meta["fps"]) == (640, 360, 30.0)
    first = np.frombuffer(next(reader), np.uint8).reshape(h, w, 3).astype(int)
    reader.close()
    # The balls (id colours, saturated) lie on one row in the upper third, left to right
    # around the centre; the floor (grey) fills the lower half.
    saturated = (first.max(axis=2) - first.min(axis=2)) > 80
    rows, cols = np.nonzero(saturated)
    assert rows.size > 300 and rows.max() < h / 3 and cols.min() > w / 4 and cols.max() < 3 * w / 4
    assert np.median(first[h // 2 :]) < 240  # not the white background


def test_arrays_nested_too_deep_for_the_parser_are_one_line(tmp_path):
    # 3,000 levels: the TOML parser itself runs out of stack (RecursionError)
    text = '# a comment with [[[ brackets\n[world]\nmethod = "verlet" # "[["\n\n[[particles]]\ntype = "list"\npositions = ' + "[" * 3000 + "]" * 3000 + "\n"
    lines, path = errors_of(text, tmp_path)
    assert lines == [f"{path}: line 7: particles[0].positions: {'[' * 32}... is invalid: arrays and tables nested more than 32 levels deep are refused"]


def test_values_nested_too_deep_are_one_line(tmp_path):
    # parsed, but deeper than any scene needs: refused before validation (whose messages
    # would print the whole value, and whose repr of it could itself recurse too deep)
    lines, path = errors_of(ONE.replace("[[0, 0, 0]]", "[" * 100 + "]" * 100), tmp_path)
    assert lines == [f"{path}: particles[0].positions[0][0][0]...: {'[' * 40}... is invalid: arrays and tables nested more than 32 levels deep are refused"]
    lines, _ = errors_of("[render.camera." + ".".join(["a"] * 3000) + "]\n", tmp_path)
    assert len(lines) == 1 and lines[0].startswith(f"{path}: render.camera.a.a.a.a...: {{'a': {{'a': ") and "nested more than 32 levels deep" in lines[0]


def test_an_integer_too_long_to_read_is_one_line(tmp_path):
    lines, path = errors_of("[world]\ndt = " + "1" * 5000 + "\n", tmp_path)
    assert len(lines) == 1 and lines[0].startswith(f"{path}: cannot be read as TOML: ") and "4300 digits" in lines[0]


def test_particle_count_is_known_without_building():
    scenes = {p.name: Scene.from_toml(p) for p in SCENES.glob("*.toml")}
    assert scenes["sand_box.toml"].particle_count() == 2000
    assert scenes["newtons_cradle.toml"].particle_count() == 10
    assert scenes["demo.toml"].particle_count() == 400
    huge = Scene.from_string('[[particles]]\ntype = "random"\nlo = [0, 0, 0]\nhi = [1, 1, 1]\ncount = 1000000000\n')
    assert huge.particle_count() == 10**9  # counted, not made


def test_sleeping_settings_go_through_scene_files(tmp_path):
    """[collisions] sleep_time and sleep_speed reach the world; a world in which nothing sleeps
    (sleep_time=None) is written as sleep_time = inf (TOML has no None) and read back as None."""
    path = tmp_path / "s.toml"
    path.write_text('[[forces]]\ntype = "gravity"\n[collisions]\nsleep_time = 0.25\nsleep_speed = 0.002\n')
    w = kinema.load_scene(path)
    assert (w.collisions["sleep_time"], w.collisions["sleep_speed"]) == (0.25, 0.002)
    w = kinema.World()
    w.set_collisions(sleep_time=None)
    again = kinema.load_scene(w.to_scene().to_toml(tmp_path / "off.toml"))
    assert "sleep_time = inf" in (tmp_path / "off.toml").read_text()
    assert again.collisions["sleep_time"] is None and w.collisions["sleep_time"] is None
    w.set_collisions(sleep_time=float("inf"))
    assert w.collisions["sleep_time"] is None
