"""The force models' sub-models (issue 50): the engine's register of LAMMPS GRANULAR's five
parts of a contact (`crates/kinema/src/collide/contact_force/sub_models.rs`, `SUB_MODELS`,
read here as `_core.CONTACT_SUB_MODELS`) is the table docs/collisions.md shows, every setting
it names is a keyword of `World.set_collisions`, and each row's settings choose that law
(the physics: each law's force against its closed form, in test_jkr.py, test_hertz.py,
test_tangential.py and the others; here, that the settings named in the table are the ones
that change the contact)."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema import _core

DOC = Path(__file__).resolve().parent.parent / "docs" / "collisions.md"
KINDS = ("normal", "damping", "tangential", "rolling", "twisting")


def _doc_rows() -> list[tuple[str, str, str, str]]:
    text = DOC.read_text(encoding="utf-8")
    section = text.split("### The sub-models, as LAMMPS GRANULAR composes them", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0] in KINDS:
            rows.append((cells[0], cells[1].strip("`"), cells[2].strip("`"), cells[3]))
    return rows


def test_the_register_is_the_table_in_the_docs():
    assert [tuple(r) for r in _core.CONTACT_SUB_MODELS] == _doc_rows()


def test_the_register_has_every_part_of_a_lammps_contact():
    assert {r[0] for r in _core.CONTACT_SUB_MODELS} == set(KINDS)
    names = [(r[0], r[1]) for r in _core.CONTACT_SUB_MODELS]
    assert len(names) == len(set(names))
    tangential = [r[1] for r in _core.CONTACT_SUB_MODELS if r[0] == "tangential"]
    assert tangential == list(_core.TANGENTIAL_MODELS)


def test_every_setting_the_register_names_is_a_keyword_of_set_collisions():
    keywords = set(inspect.signature(kinema.World.set_collisions).parameters)
    for kind, name, _, chosen_by in _core.CONTACT_SUB_MODELS:
        words = set(re.findall(r"\b([a-z_]+)\s*(?:=|>|\(|,|$)", chosen_by)) - {"the", "with", "default", "rolling", "sds"}
        assert words, (kind, name)
        assert words <= keywords, (kind, name, words - keywords)


def _bounce(**collisions) -> np.ndarray:
    """A spinning ball dropped at an angle on a floor: its velocity and spin after 300 steps."""
    w = kinema.World(dim=3, dt=2e-5, spin=True)
    w.add_particles([[0.0, 0.0, 0.0105]], velocity=[[0.3, 0.0, -0.5]], mass=1e-3, radius=0.01, angular_velocity=[[0.0, 40.0, 5.0]])
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(**collisions)
    w.step(300)
    return np.r_[w.velocities[0], w.angular_velocities[0]]


@pytest.mark.parametrize(
    ("row", "base", "changed"),
    [
        ("damping mass_velocity", dict(model="spring_dashpot", stiffness=1e4, restitution=0.5), dict(damping=50.0)),
        (
            "tangential mindlin",
            dict(model="hertz", youngs_modulus=1e7, restitution=0.5, friction=0.5, tangential="linear_history", tangential_stiffness=2e3),
            dict(tangential="mindlin", tangential_stiffness=None),
        ),
        ("rolling sds", dict(model="spring_dashpot", stiffness=1e4, restitution=0.5, friction=0.5), dict(rolling_friction=0.2)),
        ("normal dmt", dict(model="hertz", youngs_modulus=1e7, restitution=0.5), dict(cohesion="dmt", surface_energy=5.0)),
    ],
)
def test_the_settings_a_row_names_choose_its_law(row, base, changed):
    """Each row's settings change the contact: a ball's bounce differs from the one without."""
    kind, name = row.split()
    assert (kind, name) in {(r[0], r[1]) for r in _core.CONTACT_SUB_MODELS}
    before = _bounce(**base)
    after = _bounce(**{**base, **changed})
    assert np.all(np.isfinite(after))
    assert not np.array_equal(before, after), row


@pytest.mark.parametrize(
    ("collisions", "expected"),
    [
        (dict(model="spring_dashpot", stiffness=1e4), {"normal": "hooke", "damping": "coeff_restitution"}),
        (
            dict(model="spring_dashpot", stiffness=1e4, damping=20.0, friction=0.3),
            {"normal": "hooke", "damping": "mass_velocity", "tangential": "linear_history"},
        ),
        (
            dict(model="hertz", youngs_modulus=1e7, friction=0.3, rolling_friction=0.1),
            {"normal": "hertz", "damping": "coeff_restitution", "tangential": "mindlin", "rolling": "sds", "twisting": "marshall"},
        ),
        (dict(model="hertz", youngs_modulus=1e7, cohesion="jkr", surface_energy=0.1), {"normal": "jkr", "damping": "coeff_restitution"}),
        (dict(model="hertz", youngs_modulus=1e7, cohesion="dmt", surface_energy=0.1), {"normal": "dmt", "damping": "coeff_restitution"}),
        (dict(model="impulse", friction=0.3), None),
    ],
)
def test_a_world_names_the_sub_models_of_its_contacts(collisions, expected):
    """`contact_sub_models()` names what the settings chose, in LAMMPS's order, and only the
    parts that act (no tangential part without friction)."""
    w = kinema.World(dim=3, spin=True)
    assert w.contact_sub_models() is None
    w.set_collisions(**collisions)
    got = w.contact_sub_models()
    assert got == expected
    if got is not None:
        assert list(got) == [k for k in KINDS if k in got]
        assert set(got.items()) <= {(r[0], r[1]) for r in _core.CONTACT_SUB_MODELS}
