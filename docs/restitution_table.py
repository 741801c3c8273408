"""The restitution a spring–dashpot or Hertzian contact comes out with against the one set,
by the number of steps of velocity Verlet the contact spans: the table of docs/collisions.md
("Contact time").

    python docs/restitution_table.py [--method verlet]

Each entry is one head-on pair (``kinema.contact_time.restitution_at``: m* = 1 kg, ω₀ = 1
rad/s, or k_h = 1 N/m^(3/2) at 1 m/s; the ratio depends on dt / t_c alone).
"""

from __future__ import annotations

import argparse

from kinema.contact_time import restitution_at

STEPS = (5, 10, 20, 50, 100, 1000)
RESTITUTIONS = (0.1, 0.3, 0.5, 0.9, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--method", default="verlet")
    args = parser.parse_args()
    print(f"e measured, method {args.method!r}, by steps per contact t_c / dt")
    print("| model | e set | " + " | ".join(f"{s}" for s in STEPS) + " |")
    print("|---|---|" + "---|" * len(STEPS))
    for model in ("spring_dashpot", "hertz"):
        for e in RESTITUTIONS:
            row = [restitution_at(model, args.method, s, e) for s in STEPS]
            print(f"| {model} | {e} | " + " | ".join(f"{x:.4f}" for x in row) + " |")


if __name__ == "__main__":
    main()
