"""``asbuilt calibrate SCAN --targets TARGETS --out CAL [--initial CAL] [--free ...] [--fix ...]``.

Estimates the pan-tilt/range finder calibration by least squares from a scan of known targets
(planes, spheres, surveyed points; docs/calibration.md). The scan must carry each object's raw
``measurements`` (``asbuilt scan`` writes them). Prints the residual before and after, each
estimated parameter with its standard error, and the parameters held fixed because the targets
cannot tell them apart; writes the calibration file atomically. ``SCAN`` may be ``-`` (standard
input, :mod:`asbuilt.cli._input`).
"""

from __future__ import annotations

import argparse

from asbuilt.cli._input import SCAN_HELP
from asbuilt.cli._text import plural

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``calibrate`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "calibrate",
        help="estimate the scanner's calibration from scans of known targets",
        description="Fit the kinematic chain's parameters (axis zeros and scales, tilt axis "
        "offset, lever arm, beam misalignment, range offset and scale, base pose) to shots at "
        "known targets by least squares.",
        epilog="Example: asbuilt calibrate room.json --targets room.targets.json --out rig.cal.json",
    )
    parser.add_argument(
        "scan", metavar="SCAN", help=f"asbuilt-scan file with measurements ({SCAN_HELP})"
    )
    parser.add_argument(
        "--targets",
        required=True,
        metavar="FILE",
        help="asbuilt-targets file: object id -> known plane/sphere/point",
    )
    parser.add_argument(
        "--initial",
        metavar="FILE",
        help="starting calibration (signs are taken from it; default ideal)",
    )
    parser.add_argument(
        "--out", "-o", required=True, metavar="FILE", help="calibration file to write"
    )
    parser.add_argument(
        "--free",
        metavar="NAMES",
        help="comma-separated parameters to estimate (default: the observable ones)",
    )
    parser.add_argument(
        "--fix",
        metavar="NAMES",
        default="",
        help="comma-separated parameters to hold at their initial values",
    )
    parser.add_argument(
        "--robust", action="store_true", help="soft-L1 loss: resist a few stray shots"
    )
    parser.set_defaults(handler=run)
    return parser


def _parameter_choices(free_text: str | None, fix_text: str | None):
    """The ``--free`` names (None: the observable ones) and the ``--fix`` names.

    Raises
    ------
    CalibrationError
        A name that is no parameter, ``--free`` given without a name, or a name given to both
        (the estimate then said no parameter was observable, or ignored the choice).
    """
    from asbuilt.drivers.kinematics import PARAMETERS
    from asbuilt.errors import CalibrationError

    chosen = {}
    for option, text in (("--free", free_text), ("--fix", fix_text)):
        names = [n.strip() for n in (text or "").split(",") if n.strip()]
        if text and not names:
            raise CalibrationError(
                "give parameter names, comma separated (e.g. pan_zero,range_offset)", where=option
            )
        for name in names:
            if name not in PARAMETERS:
                raise CalibrationError(
                    f"unknown parameter {name!r}; use names from: {', '.join(PARAMETERS)}",
                    where=option,
                )
        chosen[option] = names
    both = [n for n in chosen["--free"] if n in chosen["--fix"]]
    if both:
        raise CalibrationError(
            f"{both[0]!r} is given to both --free and --fix; estimate it or hold it, not both",
            where="--fix",
        )
    return (chosen["--free"] if free_text else None), chosen["--fix"]


def run(args: argparse.Namespace) -> int:
    """Load, estimate, print, write; return 0."""

    import numpy as np
    from rich.console import Console
    from rich.table import Table

    from asbuilt.atomic import check_target
    from asbuilt.cli._args import refuse_standard_output
    from asbuilt.cli._input import input_files, scan_input
    from asbuilt.drivers.calibration import (
        TargetShots,
        estimate_calibration,
        file_key,
        file_value,
        load_calibration,
        load_targets,
        save_calibration,
    )
    from asbuilt.drivers.kinematics import Calibration
    from asbuilt.errors import CalibrationError

    _parameter_choices(args.free, args.fix)  # before any work: a typo in a name
    # Before any work: the calibration must not replace the scan's measurements, the targets or
    # the initial calibration, and its directory must exist.
    refuse_standard_output(
        args.out, "--out", "the calibration (its table is printed there)", "rig.cal.json"
    )
    check_target(
        args.out,
        "--out",
        inputs=input_files(args.scan, args.targets, args.initial),
        example="rig.cal.json",
    )
    source = scan_input(args.scan)
    scan = source.load_scan()
    targets = load_targets(args.targets)
    initial = load_calibration(args.initial) if args.initial else Calibration()
    shots = []
    for name, target in targets.items():
        try:
            obj = scan.object(name)
        except KeyError:
            raise CalibrationError(
                "no object with this id in the scan; scan it or remove it from the targets",
                source=args.targets,
                where=f"targets.{name}",
            ) from None
        if obj.measurements is None:
            raise CalibrationError(
                "has no raw measurements; scan it with asbuilt scan (which records them)",
                source=source.name,
                where=obj.where,
            )
        m = np.asarray(obj.measurements, float)
        shots.append(TargetShots(name, target, m[:, 0], m[:, 1], m[:, 2]))
    free, fix = _parameter_choices(args.free, args.fix)
    result = estimate_calibration(
        shots, initial, free=free, fixed=fix, loss="soft_l1" if args.robust else "linear"
    )
    save_calibration(result.calibration, args.out, estimate=result.summary())

    out = Console(markup=False)
    table = Table(
        title=f"calibration from {plural(result.n_shots, 'shot')} at {plural(len(shots), 'target')}"
    )
    for col in ("parameter", "initial", "estimate", "stderr"):
        table.add_column(col, justify="left" if col == "parameter" else "right")
    for name in result.free:  # in the file's units (file_value: degrees, metres, ratios)
        unit = " deg" if "_deg" in file_key(name) else (" m" if "_m" in file_key(name) else "")
        table.add_row(
            name,
            f"{file_value(name, initial.get(name)):.6g}{unit}",
            f"{file_value(name, result.calibration.get(name)):.6g}{unit}",
            f"{file_value(name, result.stderr[name]):.2g}{unit}",
        )
    out.print(table)
    out.print(
        f"residual RMS: {result.initial_rms * 1000:.2f} mm before, "
        f"{result.residual_rms * 1000:.2f} mm after"
    )
    for name, rms in result.per_target_rms.items():
        out.print(f"  {name}: {rms * 1000:.2f} mm")
    # Each note is one line: soft_wrap leaves the wrapping to the terminal (rich's own wrapping
    # broke the list after a comma, as if the line ended there).
    if result.fixed:
        out.print(
            "held fixed (not observable from these targets): " + ", ".join(result.fixed),
            soft_wrap=True,
        )
    if result.correlated:
        pairs = ", ".join(f"{a} ~ {b} ({rho:+.2f})" for a, b, rho in result.correlated)
        out.print(
            "strongly correlated (these targets determine mainly each pair's combination, "
            f"not the values apart): {pairs}",
            soft_wrap=True,
        )
    if result.one_target:
        notes = []
        for name, target in result.one_target.items():
            moved = file_value(name, result.calibration.get(name) - initial.get(name))
            unit = " deg" if "_deg" in file_key(name) else (" m" if "_m" in file_key(name) else "")
            notes.append(f"{name} by {target} (moved {moved:+.3g}{unit})")
        out.print(
            "set by one target's pose alone (an error in that pose moves it undetected): "
            + ", ".join(notes),
            soft_wrap=True,
        )
    out.print(f"wrote {args.out}")
    return 0
