"""The ``simulate`` and ``render`` sub-commands; :func:`register` adds them to the ``bootmap`` command.

Each handler is a thin shell over a library call and returns an exit code: 0 success, 1 failure (the
robot got stuck), 2 bad input (a malformed world or run file), with the message on stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .. import arguments
from ..errors import EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK, BootmapError, TableauError, WorldError, error_line


def register(subparsers) -> None:
    """Add ``simulate`` and ``render`` to an ``argparse`` sub-parsers object."""
    p = subparsers.add_parser(
        "simulate", help="run the simulated robot in a world and write its tableau (images, actions, truth)",
        description="Run the simulated robot (pymunk physics, a 180-beam laser, control laws that see only "
                    "the scan and odometry) in a world, and write the tableau of its dstates as JSON.")
    p.add_argument("world", help="world file, or the name of one in worlds/ (e.g. notched_rectangle)")
    p.add_argument("--policy", choices=("circuits", "explore", "active", "random"),
                   help="circuits of a room; systematic exploration of a hallway; active mapping (explore and "
                        "rehearse until the robot's own map is unique and complete; --steps caps it); a random "
                        "walk (needs --steps) (default: the world's)")
    p.add_argument("--circuits", type=arguments.count("circuits"), default=50, metavar="N", help="circuits to make (default 50)")
    p.add_argument("--steps", type=arguments.count("steps", 2), metavar="N",
                   help="record exactly N dstates (explore: keep wandering after exploring)")
    p.add_argument("--direction", choices=("cw", "ccw"), default="cw", help="direction of circuits")
    p.add_argument("--seed", type=arguments.count("seed", 0), default=0, help="random seed (default 0); same seed, same tableau")
    p.add_argument("--set", type=arguments.setting, action="append", metavar="SECTION.FIELD=VALUE",
                   help="override a field of the world file, e.g. --set motion_noise.turn_scale=0; validated "
                        "as in the file; repeatable")
    p.add_argument("-o", "--output", metavar="FILE", help="write the tableau here (default: stdout)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_simulate)

    r = subparsers.add_parser(
        "render", help="draw a world, and optionally a run's trajectory, dstates and one image",
        description="Draw a world (walls, clutter, places) to an image file; with --run, also the robot's "
                    "trajectory and its true dstates, numbered, with their headings.")
    r.add_argument("world", help="world file, or the name of one in worlds/")
    r.add_argument("--run", metavar="RUN.json", help="a tableau written by `bootmap simulate`")
    r.add_argument("--image", type=int, metavar="STEP", help="also draw the image of this step as laser rays")
    r.add_argument("-o", "--output", required=True, metavar="FILE", help="image file (.png, .svg, .pdf)")
    r.set_defaults(handler=cmd_render)


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..agent import make_policy
    from .simulation import SimulationError, run
    from .world import load_world

    try:
        world = load_world(args.world, dict(args.set or ()))
        if args.circuits < 1 or (args.steps is not None and args.steps < 1):
            raise WorldError("--circuits and --steps must be at least 1")
        if args.policy == "random" and args.steps is None:
            raise WorldError("--policy random never stops by itself: give --steps N")
        policy = make_policy(args.policy or world.policy, world, args.steps, args.direction)
        result = run(world, policy=policy, circuits=args.circuits, steps=args.steps,
                     seed=args.seed, progress=not args.no_progress, direction=args.direction)
    except SimulationError as e:
        print(error_line("simulate", e, EXIT_FAILURE), file=sys.stderr)
        return EXIT_FAILURE
    except (WorldError, OSError) as e:
        print(error_line("simulate", e, EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    text = result.tableau.dumps()
    if args.output:
        try:
            Path(args.output).write_text(text + "\n")
        except OSError as e:
            print(error_line("simulate", f"cannot write {args.output}: {e.strerror}", EXIT_FAILURE), file=sys.stderr)
            return EXIT_FAILURE
        truths = {s.truth for s in result.tableau.steps}
        print(f"{args.output}: {len(result.tableau)} dstate images from {len(truths)} true dstates, "
              f"{result.sim_time:.0f} s simulated in {result.wall_time:.1f} s", file=sys.stderr)
    else:
        print(text)
    return EXIT_OK


def cmd_render(args: argparse.Namespace) -> int:
    from ..tableau import load
    from .render import render
    from .world import load_world

    try:
        world = load_world(args.world)
        tableau = load(args.run) if args.run else None
        if args.image is not None and (tableau is None or not 0 <= args.image < len(tableau)):
            raise TableauError(f"--image {args.image} needs --run with at least {args.image + 1} steps")
        render(world, tableau, image_step=args.image, path=args.output)
    except (WorldError, TableauError) as e:
        print(error_line("render", e, EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    except (BootmapError, OSError, ValueError) as e:
        print(error_line("render", e, EXIT_FAILURE), file=sys.stderr)
        return EXIT_FAILURE
    print(f"wrote {args.output}", file=sys.stderr)
    return EXIT_OK
