"""The collision part of ``kinema.World``'s API: the settings (``set_collisions``,
``collisions``), the colliders added, the periodic axes, what the collision stages report
(``contacts``, ``collision_stats``, ``collider_books``) and the time each stage of a step took
(``stage_times``). ``WorldCollisions`` is a base class of ``World``, not used alone: its
methods use the world's engine (``_core``), its views (``_push``, ``_pull``), its colliders
(``_colliders``, which ``World.add`` fills), its ``dim`` and the advisor's flag
(``_advice_due``). Units: m, s, kg; impulses N·s, energies J."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _checks, _core
from .colliders import Collider

# The engine's defaults (kinema::world::CollisionParams::default), read once: the one place
# they are kept.
_DEFAULTS = _core.collision_defaults()


class WorldCollisions:
    """Collisions of a ``kinema.World``: see ``World`` and docs/collisions.md."""

    # Over 100 lines (issue 50) by its documentation alone: 22 settings, in the signature (25
    # lines, each default the engine's) and each described in the docstring (80 lines, the
    # public reference of every collision setting); the code (31 lines) checks each setting's
    # type and hands them to the engine, which checks their values together.
    def set_collisions(
        self,
        model: str = _DEFAULTS["model"],
        restitution: float = _DEFAULTS["restitution"],
        friction: float = _DEFAULTS["friction"],
        ccd: bool = _DEFAULTS["ccd"],
        restitution_threshold: float | None = _DEFAULTS["restitution_threshold"],
        sleep_time: float | None = _DEFAULTS["sleep_time"],
        sleep_speed: float | None = _DEFAULTS["sleep_speed"],
        stiffness: float | None = _DEFAULTS["stiffness"],
        damping: float | None = _DEFAULTS["damping"],
        event_driven: bool = _DEFAULTS["event_driven"],
        youngs_modulus: float | None = _DEFAULTS["youngs_modulus"],
        poisson_ratio: float | None = _DEFAULTS["poisson_ratio"],
        cohesion: str | None = _DEFAULTS["cohesion"],
        surface_energy: float | None = _DEFAULTS["surface_energy"],
        rolling_friction: float = _DEFAULTS["rolling_friction"],
        tangential: str | None = _DEFAULTS["tangential"],
        tangential_stiffness: float | None = _DEFAULTS["tangential_stiffness"],
        tangential_damping: float | None = _DEFAULTS["tangential_damping"],
        rolling_stiffness: float | None = _DEFAULTS["rolling_stiffness"],
        rolling_damping: float | None = _DEFAULTS["rolling_damping"],
        accuracy: str = _DEFAULTS["accuracy"],
        self_collisions: bool = _DEFAULTS["self_collisions"],
    ) -> None:
        """Turn collisions on, or replace every one of their settings.

        ``model``: ``"impulse"`` (Newton's restitution law u_n⁺ = −e u_n⁻ by impulses after
        each integration step) or ``"spring_dashpot"`` (a force k_n δ − m_eff γ_n u_n while
        two bodies overlap by δ, integrated with the other forces; it needs ``stiffness`` k_n
        in N/m, and ``damping`` γ_n in 1/s defaults to the value that gives ``restitution``)
        or ``"hertz"`` (Hertz's elastic spheres, the same way: F_n = 4/3 E* √R* δ^(3/2) −
        c_n u_n, R* = r_i r_j/(r_i + r_j), E* = E/(2(1 − ν²)) from ``youngs_modulus`` E in Pa
        and ``poisson_ratio`` ν (default 0.3), the dashpot 2 ζ √(k_n m_eff) at the current
        stiffness k_n = 4/3 E* √(R* δ) with ζ from ``restitution``: LAMMPS's
        ``hertz/material`` with ``damping coeff_restitution``).
        ``restitution`` e ∈ [0, 1] and ``friction`` (Coulomb μ ≥ 0) are the values of every
        particle without its own. ``ccd``: find impacts at their time inside the step, so
        nothing passes through a particle or a wall however fast. ``restitution_threshold``
        (m/s): approach speeds below it bounce with e = 0, so resting contacts stay at rest;
        ``None`` takes twice the largest speed change the forces gave a particle in the step.
        ``sleep_time`` (s, default 0.5; ``None``: nothing sleeps): an island of touching
        particles that rests on a collider, and whose particles have all been slower than
        ``sleep_speed`` (m/s; ``None``: the largest speed change the forces gave a particle in
        the step, g·dt under gravity) for that long, sleeps: velocities exactly 0, no work
        until an impact, a touch, a write or a change of forces or colliders wakes it
        (Box2D's, Bullet's and Chipmunk's sleeping; docs/collisions.md).

        ``rolling_friction`` μ_r ≥ 0 (a world with spin): resting and rolling contacts resist
        the two bodies' relative turning, rolling and twisting. The impulse model: with a
        torque of at most μ_r R* F_n, R* = r_i r_j/(r_i + r_j) (r against a collider), as
        LAMMPS's ``rolling sds`` and ``twisting sds`` at their sliders' limit: a ball rolling
        on a floor slows at 5/7 μ_r g, one on a slope of tan θ ≤ μ_r stays put. The force
        models: LAMMPS's ``rolling sds`` (a spring ``rolling_stiffness`` k_r in N/m, default
        the contact's k_t, and dashpot ``rolling_damping`` γ_r in kg/s, default its γ_t, on
        the rolling displacement R* (ω_i − ω_j) × n, its force capped at μ_r |F_n|) and
        ``twisting marshall``.

        Friction with the force models (``"spring_dashpot"``, ``"hertz"``): wherever a contact
        has μ > 0 it has a tangential spring with memory, F_t = −k_t ξ − γ_t v_t capped at
        μ |F_n| (LAMMPS's ``tangential``): ``tangential="linear_history"`` (the default with
        ``"spring_dashpot"``; k_t = ``tangential_stiffness`` N/m, default 2/7 k_n) or
        ``"mindlin"`` (the default with ``"hertz"``: k_t = 8 G* √(R* δ) from E and ν);
        ``tangential_damping`` x_γt ≥ 0 (default 0.5) makes γ_t = x_γt c_n. The springs
        stretch once per step: such a world steps with ``method="verlet"`` only, and with spin
        the torques turn the particles (velocity Verlet for ω, as LAMMPS's ``fix
        nve/sphere``). docs/collisions.md has the formulas.

        ``cohesion`` (with ``"hertz"``), adhesion of touching bodies by their ``surface_energy``
        γ in J/m² (LAMMPS GRANULAR's ``dmt`` and ``jkr``; w = 2γ the work of adhesion):
        ``"dmt"`` pulls overlapping bodies together by 4π γ R* and lets go at δ = 0;
        ``"jkr"`` follows Johnson–Kendall–Roberts' contact, which, once made, holds past
        δ = 0 until it is pulled apart at 3π γ R* (it remembers its touches, so it steps with
        ``method="verlet"`` only).

        ``event_driven``: with the impulse model and no forces (a gas), run from frame to
        frame by events instead of steps: every impact at its exact time, by the same rule,
        one scheduled event per particle (Smallenburg's event-driven dynamics; much faster for
        gases, docs/collisions.md). Colliders must be still planes and boxes; a step of such a
        world refuses anything else with a ValueError that says why.

        ``accuracy`` (the impulse model, stepped): ``"physics"`` (the default) solves each
        step's resting contacts by action and reaction alone, up to 100 sweeps a step, and
        holds piles at 0.2–0.3 % of r at ``dt = 1e-3``; ``"animation"`` adds shock
        propagation (the pile's levels stopped bottom up, each on its supports held still;
        Guendelman et al. 2003) with up to 10 sweeps of the solve, and holds deep piles at rest within
        about 1 % of r at ``dt = 1/120``, several times faster. Its pushes are taken up by
        the ground rather than by the particles below: momentum is not exchanged by action and
        reaction there (docs/collisions.md, "The accuracy setting").

        ``self_collisions=False``: particles never collide with each other, only with the
        colliders (Blender's particles; a fountain's jet that does not burst into spray). It
        overrides the groups' matrix (:meth:`set_group_collisions`), which says which particle
        pairs collide when it is true (the default).

        With ``"spring_dashpot"`` and ``"hertz"`` the contacts are a force (its elastic energy is the potential
        ``"contact"`` of :meth:`diagnostics` and of the ``Trajectory``), which the stable-step
        advisor and the ``StabilityWarning`` count; :meth:`contacts` reports the impulse model
        only (:meth:`collision_stats` reports both: the contacts, those begun, the dashpots'
        energy).

        ``w.set_collisions(**w.collisions)`` changes nothing. The defaults are the engine's
        (``model="impulse"``, ``restitution=1.0``, ``friction=0.0``, ``ccd=True``,
        ``sleep_time=0.5``, ``event_driven=False``, ``accuracy="physics"``, ``self_collisions=True``, the rest ``None``), read from it.
        """
        settings = {
            "model": _checks.text("model", model),
            "restitution": _checks.real("restitution", restitution),
            "friction": _checks.real("friction", friction),
            "ccd": _checks.boolean("ccd", ccd),
            "restitution_threshold": _checks.real("restitution_threshold", restitution_threshold, optional=True),
            "sleep_time": _checks.real("sleep_time", sleep_time, optional=True),
            "sleep_speed": _checks.real("sleep_speed", sleep_speed, optional=True),
            "stiffness": _checks.real("stiffness", stiffness, optional=True),
            "damping": _checks.real("damping", damping, optional=True),
            "youngs_modulus": _checks.real("youngs_modulus", youngs_modulus, optional=True),
            "poisson_ratio": _checks.real("poisson_ratio", poisson_ratio, optional=True),
            "cohesion": None if cohesion is None else _checks.text("cohesion", cohesion),
            "surface_energy": _checks.real("surface_energy", surface_energy, optional=True),
            "event_driven": _checks.boolean("event_driven", event_driven),
            "rolling_friction": _checks.real("rolling_friction", rolling_friction),
            "tangential": None if tangential is None else _checks.text("tangential", tangential),
            "tangential_stiffness": _checks.real("tangential_stiffness", tangential_stiffness, optional=True),
            "tangential_damping": _checks.real("tangential_damping", tangential_damping, optional=True),
            "rolling_stiffness": _checks.real("rolling_stiffness", rolling_stiffness, optional=True),
            "rolling_damping": _checks.real("rolling_damping", rolling_damping, optional=True),
            "accuracy": _checks.text("accuracy", accuracy),
            "self_collisions": _checks.boolean("self_collisions", self_collisions),
        }
        if settings["rolling_friction"] and not self._core.spin:
            raise ValueError(
                f"rolling_friction = {rolling_friction!r} is invalid: rolling resistance acts on turning particles; make the world with kinema.World(..., spin=True)"
            )
        self._push()
        self._core.set_collisions(settings)
        self._advice_due = True  # the spring-dashpot model's contacts are stiff springs

    def set_group_collisions(self, a: Any, b: Any, collide: bool = True) -> None:
        """Say whether collision groups ``a`` and ``b`` collide (both ways: the matrix stays
        symmetric; Box2D's category and mask bits, Bullet's collision filter groups). ``a`` and
        ``b`` are groups (integers in 0..31) or lists of them: every pair (one of ``a``, one of
        ``b``) is set. ``set_group_collisions(1, 1, False)``: group 1's particles pass through
        each other; ``set_group_collisions(0, 1, False)``: groups 0 and 1 pass through each
        other, each still colliding with itself. Every pair collides by default; a particle's
        group is :attr:`groups` (``add_particles(..., group=k)``), a collider's groups its
        ``collides_with``. Turns collisions on if they are off. Contacts, islands and the
        neighbour lists start over."""
        ga = _checks.groups("a", a).reshape(-1).tolist()
        gb = _checks.groups("b", b).reshape(-1).tolist()
        on = _checks.boolean("collide", collide)
        matrix = self.collision_matrix.copy()
        for i in ga:
            for j in gb:
                matrix[i, j] = matrix[j, i] = on
        self.collision_matrix = matrix

    @property
    def collision_matrix(self) -> np.ndarray:
        """Which collision groups collide: a (32, 32) symmetric bool array (a copy), entry
        [a, b] true when particles of groups a and b collide (all true by default). Assign a
        (32, 32) symmetric bool array to set it whole; :meth:`set_group_collisions` sets pairs.
        ``set_collisions(self_collisions=False)`` turns every pair off over it."""
        rows = np.asarray(self._core.group_masks, dtype=np.uint64)
        return (rows[:, None] >> np.arange(_checks.GROUPS, dtype=np.uint64)[None, :]) & 1 == 1

    @collision_matrix.setter
    def collision_matrix(self, value: Any) -> None:
        m = _checks.bool_array("collision_matrix", value)
        n = _checks.GROUPS
        if m.shape != (n, n):
            raise ValueError(f"collision_matrix has shape {m.shape}; it must be ({n}, {n}): one row and column per collision group")
        bad = np.argwhere(m != m.T)
        if bad.size:
            a, b = (int(k) for k in bad[0])
            raise ValueError(
                f"collision_matrix[{a}][{b}] = {bool(m[a, b])} is invalid: the matrix must be symmetric "
                f"(collision_matrix[{b}][{a}] is {bool(m[b, a])}); groups {a} and {b} collide or not both ways"
            )
        rows = [int(np.sum(np.left_shift(np.uint64(1), np.arange(n, dtype=np.uint64))[row])) for row in m]
        self._push()
        self._core.set_group_masks(rows)

    def contact_time(self) -> float | None:
        """The duration of the shortest contact the scene can produce, s, with the
        ``"spring_dashpot"`` or ``"hertz"`` model (``None`` with the impulse model, and when
        no contact can happen: for Hertz, while nothing moves and nothing can fall onto
        anything): half a damped period π / (ω₀ √(1 − ζ²)) of the lightest pair's spring
        (ω₀² = k_n / m*), or a Hertzian impact's 2.868 (m*² / (R* E*² u))^(1/5) at the fastest
        approach the particles' speeds, their fall under gravity onto the colliders (and the
        colliders' motion) and the emitters allow (``kinema.first_step``). A step should span
        at least 20 of it, and with Hertz stay under 0.2 of the particles' Rayleigh time:
        before the first step, a coarser one warns (``ContactTimeWarning``) with the safe
        step and the restitution it gives instead of the one set."""
        from . import first_step

        self._push()
        found = first_step.check(self, self._core)
        return None if found is None or found.contact is None else found.contact.t_c

    @property
    def collisions(self) -> dict | None:
        """The collision settings, a dict of :meth:`set_collisions`' keyword arguments, or
        ``None`` while collisions are off."""
        return self._core.collisions

    def contact_sub_models(self) -> dict[str, str] | None:
        """The sub-models the contact force model's contacts are made of now, as LAMMPS
        GRANULAR's ``pair granular`` names them: ``{"normal": "hertz", "damping":
        "coeff_restitution", "tangential": "mindlin", "rolling": "sds", "twisting":
        "marshall"}``, with the parts they have (a tangential part where some contact has
        friction; rolling and twisting with ``rolling_friction``), in that order. ``None``
        with the impulse model or without collisions. The table of every sub-model, with the
        settings that choose it: ``kinema._core.CONTACT_SUB_MODELS`` (docs/collisions.md)."""
        found = self._core.contact_sub_models()
        return None if found is None else dict(found)

    @property
    def colliders(self) -> list[Collider]:
        """The colliders, in the order added (a collider's index in :meth:`contacts`)."""
        return list(self._colliders)

    @property
    def periodic(self) -> tuple[bool, bool, bool]:
        """The periodic axes (x, y, z). Set ``w.periodic = (True, True, False)`` to make axes
        periodic with the cell of the world's ``Box`` (added first): its walls along those
        axes vanish and a particle leaving one side comes back on the other; positions are
        wrapped into [lo, hi) at once. All false makes space open again."""
        return self._core.periodic

    @periodic.setter
    def periodic(self, axes: Any) -> None:
        flags = _checks.bool_array("periodic", axes).reshape(-1)
        if self.dim == 2 and flags.size == 2:
            flags = np.append(flags, False)
        if flags.size != 3:
            raise ValueError(f"periodic = {_checks.describe(axes)} is invalid: it must be 3 bools (x, y, z){' or 2 in a 2D world' if self.dim == 2 else ''}")
        self._push()
        try:
            self._core.set_periodic(flags.tolist())
        finally:
            self._pull()

    def contacts(self) -> dict[str, np.ndarray]:
        """The K contacts found at the end of the last step, as detected, as arrays: ``i``
        (K,), the particle; ``j`` (K,), the other particle or −1 for a collider; ``collider``
        (K,), the collider's index in :attr:`colliders` or −1 between particles; ``normal``
        (K, 3), the unit normal from the partner towards i; ``overlap`` (K,), m, the
        penetration before it was removed; ``u_n`` (K,), m/s, (v_i − v_j)·n when the contact
        was found, before its own impulse (< 0: approaching). Impacts that continuous
        detection (``ccd``) found inside the step were resolved before, so a particle that
        bounced there shows u_n > 0. Empty with the spring–dashpot model, whose contacts live
        inside the force evaluations."""
        self._push()
        return self._core.contacts()

    def record_contact_events(self, on: bool = True) -> None:
        """Start (or stop) recording when pairs begin and end touching, as Box2D's begin and
        end touch events and Rapier's ``CollisionEvent`` give them; read them with
        :meth:`contact_events`. A pair touches at a step's end when the end-of-step solve
        gave it an impulse or its gap is at most 0, and keeps touching while its island
        sleeps; it *begins* when it touched in a step (an impact inside it counts) and did not
        at the last step's end, at its first impact's time or else at the step's end; it
        *ends* at the end of the step it stops touching in (a bounce within one step begins
        and ends there), or when one of its particles is removed. Pairs whose last contact
        carried an impulse touch already when recording starts; checkpoints and scene files do
        not keep the setting, and a change to a force model or to event-driven steps stops it. The impulse model only
        (``ValueError`` with a force model, an event-driven world, or collisions off)."""
        self._push()
        self._core.record_contact_events(bool(on))

    def contact_events(self) -> dict[str, np.ndarray]:
        """The begin and end of touch events recorded since the last call (see
        :meth:`record_contact_events`), taken out, in order (each step's begins by time,
        then its ends), as arrays of length E: ``time`` (s), ``begin`` (bool: False is an
        end), ``i`` (the particle's id, :attr:`ids`), ``j`` (the other particle's id, −1
        against a collider), ``collider`` (the index in :attr:`colliders`, −1 between
        particles) and ``impulse`` (N·s, ≥ 0: the normal impulse the pair exchanged in the
        event's step). Empty arrays when nothing was recorded."""
        return self._core.contact_events()

    def collision_stats(self) -> dict | None:
        """What the collision stages did in the last step (``"last"``) and over all steps
        (``"total"``), each a dict: ``contacts`` (at the end of the step: pairs and
        particle–collider pairs within the speculative margin, 5 % of r_i + r_j), of them
        ``resting`` (carrying an impulse at the step's end) and ``speculative`` (apart, carrying
        nothing), ``bounced`` (end-of-step contacts that bounced by Newton's law),
        ``impacts`` (found inside steps by continuous detection), ``impulses``, ``impulse_balance`` ((3,), N·s:
        the sum of the impulses between movable particles, 0 by action and reaction up to
        rounding), ``energy_lost`` (J, the mechanical energy the collisions took),
        ``max_overlap`` (m: the deepest overlap in the state the step leaves), ``solver_sweeps``
        (of the end-of-step soft step's solve stage), ``islands`` (independent groups of the end-of-step contacts, each
        solved on its own) and ``unconverged`` (steps whose solver, or whose impacts, stopped
        at their cap: 0 in ``last`` means the solver converged). ``total``'s ``contacts``,
        ``resting``, ``speculative``, ``max_overlap``, ``solver_sweeps`` and ``islands`` are
        the last step's. ``None`` while collisions are off."""
        self._push()
        return self._core.collision_stats()

    def collider_books(self, last: bool = False) -> dict[str, np.ndarray]:
        """What each collider gave and took from the particles over all steps, in the order of
        :attr:`colliders` (K of them), as arrays:

        - ``momentum`` (K, 3), N·s: the momentum the particles gave the collider, −Σ J over
          the impulses J it gave them (the force it felt, integrated over time; of infinite
          mass, it does not move for it). It balances the particles' momentum change with the
          forces' impulse: Σ m Δv = −Σ_k ``momentum[k]`` + ∫ ΣF dt (m g t per particle under
          gravity; the impulses between particles cancel, by action and reaction);
        - ``angular_momentum`` (K, 3), N·m·s: the angular momentum about the origin the
          particles gave it, −Σ x_c × J, x_c the contact point on its surface;
        - ``work`` (K,), J: the work the collider did on the particles, Σ J·u(x_c) of each
          impulse J it gave with its surface velocity u there (0 for a still collider). The
          energy the collisions dissipated is ``collision_stats()["total"]["energy_lost"]``
          + Σ ``work`` (``energy_lost`` counts the particles' mechanical energy the
          collisions took, which a moving wall can give back: it is negative for a paddle
          that throws balls).

        - ``normal`` and ``tangential`` (K, 3), N·s: the parts of ``momentum`` along and
          across each contact's normal, −Σ (J·n) n and the rest: divided by the time, the
          force that presses on the collider and the shear (friction) on it, as LIGGGHTS's
          wall stress and a Janssen silo's wall pressure need.

        ``last=True`` gives what the last step alone gave (the last call of an event-driven
        world); divided by ``dt``, the step's mean forces.

        Every contact model books them: the impulse model its impacts inside steps and its
        end-of-step contacts, the event-driven model its wall impacts, the force models
        (``"spring_dashpot"``, ``"hertz"``) their contact forces integrated over the step as
        velocity Verlet applies them, h/2 (F + F'), exactly what the particles took. The force
        models book with the ``verlet`` method only (the method whose step the books come
        from; zeros with the others). Empty (K = 0) without colliders.

        A world read from a checkpoint goes on with the books of the world that wrote it, bit
        for bit.

        ``World.run`` records ``momentum``, ``normal`` and ``tangential`` at each frame
        (``Trajectory.collider_momentum``, ``collider_normal``, ``collider_tangential``;
        ``Trajectory.collider_forces()`` the mean forces between frames)."""
        self._push()
        return self._collider_books_as_pulled(last)

    def _collider_books_as_pulled(self, last: bool = False) -> dict[str, np.ndarray]:
        """:meth:`collider_books` with nothing written into the engine (the recorder's and the
        checkpoint's)."""
        return self._core.collider_books(last=bool(last))

    def _books_colliders(self) -> bool:
        """Whether the world's steps book what the particles give its colliders: not with a
        force model (``"spring_dashpot"``, ``"hertz"``) stepped by a method other than
        ``verlet``, whose steps book nothing (the engine's rule, :meth:`collider_books`)."""
        model = (self._core.collisions or {}).get("model")
        return model not in _core.FORCE_MODELS or self._core.method == "verlet"

    def stage_times(self) -> dict[str, float]:
        """Wall-clock seconds spent so far in each of the lecture notes' four stages of a step:
        ``integrate`` (forces included; with spring–dashpot contacts, those too),
        ``detect``, ``respond`` and ``distribute`` (collisions of the impulse model); and with
        collisions on, the same collision time by the impulse model's own stages, in the
        order a step runs them: ``list`` (the neighbour list holds or is rebuilt), ``impacts``
        (continuous detection, each impact at its time), ``contacts`` (the end-of-step
        contacts), ``solve`` (the soft step), ``apply`` (the totals onto both particles, the
        energy books), ``settle`` (sleeping, the largest overlap, periodic wrapping) and
        ``wake`` (a force-free world's meeting times: when each particle's straight line next
        meets another's, the engine's ``meetings`` stage; the key keeps its first name)."""
        return self._core.stage_times()
