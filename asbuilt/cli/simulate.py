"""``asbuilt simulate SCENE --out scan.json [--seed N] [--points N] [--exact]``.

Scan a scene description (``docs/scene-format.md``) with the simulated pan-tilt laser range
finder and write the result as an ``asbuilt-scan`` file, atomically. The same scene and seed
always give the same file. A one-line summary goes to standard error.
"""

from __future__ import annotations

import argparse

from asbuilt.cli._text import plural

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "simulate",
        help="simulate a pan-tilt range finder scanning a scene file",
        description="Aim a simulated pan-tilt laser range finder at every object of a scene "
        "description (docs/scene-format.md) and write the shots as an asbuilt-scan file.",
        epilog="Example: asbuilt simulate samples/scenes/spool.scene.json --out spool.json --seed 4",
    )
    parser.add_argument("scene", metavar="SCENE", help="the scene description (JSON)")
    parser.add_argument(
        "--out",
        "-o",
        metavar="FILE",
        required=True,
        help="the scan file to write ('-' for standard output)",
    )
    parser.add_argument(
        "--seed", type=int, default=None, help="random seed (default: the scene's 'seed', else 0)"
    )
    parser.add_argument(
        "--points",
        type=int,
        default=None,
        help="shots wanted on every object (default: each object's 'points')",
    )
    parser.add_argument(
        "--exact",
        action="store_true",
        help="thin every object's shots to exactly the wanted number",
    )
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Load the scene, simulate, write; return 0. Bad input raises a SceneError (exit 2)."""
    import sys

    from rich.console import Console

    from asbuilt.atomic import atomic_write, check_target
    from asbuilt.cli._args import refuse_other_format
    from asbuilt.errors import SceneError
    from asbuilt.scan.load import MAX_POINTS
    from asbuilt.sim.scene import load_scene
    from asbuilt.sim.simulate import dumps_scan, simulate_scan

    if args.seed is not None and args.seed < 0:
        raise SceneError(f"--seed must be a non-negative integer, not {args.seed}")
    if args.points is not None and args.points < 1:
        raise SceneError(f"--points must be a positive integer, not {args.points}")
    if args.points is not None and args.points > MAX_POINTS:
        raise SceneError(f"--points must be at most {MAX_POINTS:,} (the most a scan holds)")
    if args.scene == "-":
        raise SceneError(
            "simulate reads its scene from a file, not standard input; give the scene's file "
            "(e.g. samples/scenes/spool.scene.json)",
            where="SCENE -",
        )
    if args.out != "-":
        refuse_other_format(args.out, "--out", "an asbuilt-scan file", "scan.json")
        check_target(args.out, "--out", inputs=[args.scene], example="scan.json")  # before any work
    scene = load_scene(args.scene)
    doc = simulate_scan(scene, seed=args.seed, points=args.points, exact=args.exact)
    text = dumps_scan(doc)
    if args.out == "-":
        sys.stdout.write(text)
    else:
        with atomic_write(args.out, "w") as handle:
            handle.write(text)
    total = sum(len(obj["points"]) for obj in doc["objects"])
    Console(file=sys.stderr).print(
        f"simulated {plural(len(doc['objects']), 'object')}, {plural(total, 'point')} "
        f"(seed {doc['simulation']['seed']}) -> {args.out}",
        highlight=False,
    )
    return 0
