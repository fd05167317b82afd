"""``asbuilt scan --ptu URL --lrf URL --out scan.json [--plan plan.json] [--resume]``.

Runs an acquisition session with a pan-tilt head (FLIR/DP, or Pelco-D with ``--ptu-protocol
pelco-d``) and a range finder (any pyserial URL:
a device path, ``spy://`` for a traffic log, ``sim-ptu://`` / ``sim-lrf://`` simulators). For each
object the operator gives an id, a kind and a window (two corners in the unit's degrees, or
"aim" to jog the head to each corner); the session shoots a raster, fills it where the object
is, and bisects hit/miss pairs to pin the object's edges. Every shot is journaled beside the
output as it is taken; the scan file is rewritten atomically after each object; Ctrl-C, a
SIGHUP (the terminal closed) and the end of the operator's input stop cleanly, say what was saved,
and ``--resume`` continues. ``--plan`` takes the targets from a plan file instead of
prompting.

Exit codes: 0 done; 1 some objects got too few points (listed); 2 bad input or a device error
(one line; the journal keeps every shot); 130 interrupted by Ctrl-C or SIGHUP (resumable).
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``scan`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "scan",
        help="scan objects with a pan-tilt unit and a laser range finder",
        description="Run an operator (or scripted) scan session over serial devices and write "
        "an asbuilt-scan file; every shot is journaled so an interrupted session resumes.",
        epilog="Example: asbuilt scan --ptu /dev/ttyUSB0 --lrf /dev/ttyUSB1 --calibration "
        "rig.cal.json --out site.json   (add --plan plan.json for a scripted run)",
    )
    parser.add_argument(
        "--ptu",
        metavar="URL",
        required=True,
        help="pan-tilt unit: device path or pyserial URL (sim-ptu://RIG?scene=...)",
    )
    parser.add_argument(
        "--lrf",
        metavar="URL",
        required=True,
        help="range finder: device path or pyserial URL (sim-lrf://RIG)",
    )
    parser.add_argument(
        "--lrf-protocol",
        choices=("dimetix", "ldm", "lw20"),
        default="dimetix",
        help="range finder protocol (default dimetix)",
    )
    parser.add_argument(
        "--ptu-protocol",
        choices=("flir", "pelco-d"),
        default="flir",
        help="pan-tilt protocol: FLIR/DP ASCII or Pelco-D (default flir)",
    )
    parser.add_argument(
        "--ptu-baud", type=int, default=None, help="pan-tilt baud rate (flir 9600, pelco-d 2400)"
    )
    parser.add_argument(
        "--ptu-address",
        type=int,
        default=None,
        metavar="N",
        help="Pelco-D address 1-255 (1)",
    )
    parser.add_argument(
        "--ptu-tilt-sign",
        type=int,
        choices=(1, -1),
        default=None,
        help="Pelco-D: -1 if the raw tilt grows downwards (default), 1 if upwards",
    )
    parser.add_argument(
        "--ptu-tilt-encoding",
        choices=("wrap", "signed"),
        default=None,
        help="Pelco-D: how a raw tilt below zero is sent: wrap into 0-35999 (default) or "
        "signed 16-bit two's complement",
    )
    parser.add_argument(
        "--ptu-tilt-zero",
        type=float,
        default=None,
        metavar="DEG",
        help="Pelco-D: the raw tilt of the level head, degrees (0)",
    )
    parser.add_argument(
        "--lrf-baud",
        type=int,
        default=None,
        help="range finder baud rate (dimetix 19200 7E1, ldm 9600 8N1, lw20 115200 8N1)",
    )
    parser.add_argument(
        "--lrf-id",
        type=int,
        default=None,
        metavar="N",
        help="Dimetix device id 0-9 (the N of sNg; several sensors share a bus by id) (0)",
    )
    parser.add_argument(
        "--lrf-8n1",
        action="store_true",
        help="open a Dimetix sensor 8N1 instead of 7E1 (reconfigured units, ptys)",
    )
    parser.add_argument(
        "--calibration",
        metavar="FILE",
        help="asbuilt-calibration file (default: an ideal chain at the origin)",
    )
    parser.add_argument(
        "--out",
        "-o",
        metavar="FILE",
        required=True,
        help="scan file to write; the journal goes beside it (FILE.journal)",
    )
    parser.add_argument("--plan", metavar="FILE", help="asbuilt-scan-plan file (scripted mode)")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue the session recorded in the journal beside --out",
    )
    parser.add_argument("--units", default="m", help="length unit of the scan file (m)")
    parser.add_argument("--name", help="scan name")
    parser.add_argument(
        "--retries",
        type=int,
        default=None,
        help="extra attempts per failing shot before it is skipped (2)",
    )
    parser.add_argument(
        "--edge-pairs", type=int, default=None, help="hit/miss pairs bisected per object (4)"
    )
    parser.add_argument(
        "--edge-depth", type=int, default=None, help="most bisection steps per pair (10)"
    )
    parser.add_argument(
        "--edge-tolerance",
        type=float,
        default=None,
        help="bisect an edge until its bracket is this wide across the beam, in the scan's "
        "--units (0.002 m)",
    )
    parser.add_argument(
        "--keep-background",
        action="store_true",
        help="keep returns beyond the range gap in the object too",
    )
    parser.add_argument(
        "--timeout", type=float, default=3.0, help="seconds to wait for a reply (3)"
    )
    parser.add_argument(
        "--move-timeout", type=float, default=30.0, help="seconds to wait for a move to finish (30)"
    )
    parser.set_defaults(handler=run)
    return parser


def _check_devices_options(args) -> None:
    """Refuse device options the devices cannot take (one line each)."""
    import math

    from asbuilt.errors import ScanError

    for key in ("timeout", "move_timeout"):
        value = getattr(args, key)
        if not (math.isfinite(value) and value > 0):
            raise ScanError(
                f"--{key.replace('_', '-')} must be a number of seconds > 0, not {value}"
            )
    if args.lrf_id is not None:
        if args.lrf_protocol != "dimetix":
            name = {"ldm": "LDM", "lw20": "LW20"}.get(args.lrf_protocol, args.lrf_protocol)
            raise ScanError(
                f"--lrf-id is the Dimetix device id; the {name} has none (leave it out)"
            )
        if not 0 <= args.lrf_id <= 9:
            raise ScanError(f"--lrf-id must be a Dimetix device id 0-9, not {args.lrf_id}")


def _check_head_options(args) -> None:
    """Refuse pan-tilt options the chosen head cannot take (one line each)."""
    import math

    from asbuilt.errors import ScanError

    pelco = ("ptu_address", "ptu_tilt_sign", "ptu_tilt_encoding", "ptu_tilt_zero")
    if args.ptu_protocol != "pelco-d":
        for key in pelco:
            if getattr(args, key) is not None:
                raise ScanError(
                    f"--{key.replace('_', '-')} is a Pelco-D option; add --ptu-protocol pelco-d "
                    "or leave it out"
                )
    if args.ptu_address is not None and not 1 <= args.ptu_address <= 255:
        raise ScanError(f"--ptu-address must be a Pelco-D address 1-255, not {args.ptu_address}")
    if args.ptu_tilt_zero is not None and not math.isfinite(args.ptu_tilt_zero):
        raise ScanError(f"--ptu-tilt-zero must be an angle in degrees, not {args.ptu_tilt_zero}")
    if args.ptu_baud is not None and args.ptu_baud <= 0:
        raise ScanError(f"--ptu-baud must be a baud rate > 0, not {args.ptu_baud}")


def _head_options(args) -> dict:
    """Keyword options of :func:`~asbuilt.drivers.ptu.open_pan_tilt_unit` from the arguments."""
    options = {"timeout": args.timeout, "move_timeout": args.move_timeout}
    if args.ptu_baud is not None:
        options["baudrate"] = args.ptu_baud
    for key, name in (
        ("ptu_address", "address"),
        ("ptu_tilt_sign", "tilt_sign"),
        ("ptu_tilt_encoding", "tilt_encoding"),
        ("ptu_tilt_zero", "tilt_zero"),
    ):
        if getattr(args, key) is not None:
            options[name] = getattr(args, key)
    return options


def _settings(args, plan):
    from asbuilt.drivers.plan import SessionSettings

    values = dict(plan.settings) if plan is not None else {}
    for key in ("retries", "edge_pairs", "edge_depth"):
        value = getattr(args, key)
        if value is not None:
            if value < 0:
                from asbuilt.errors import ScanError

                raise ScanError(f"--{key.replace('_', '-')} must be >= 0")
            values[key] = value
    if args.edge_tolerance is not None:
        import math

        from asbuilt.units import to_metres

        if not (math.isfinite(args.edge_tolerance) and args.edge_tolerance > 0):
            from asbuilt.errors import ScanError

            raise ScanError("--edge-tolerance must be a length > 0")
        values["edge_tolerance"] = to_metres(args.edge_tolerance, args.units)
    if args.keep_background:
        values["keep_background"] = True
    return SessionSettings(**values)


class _Input:
    """The operator's answers from stdin; :attr:`ended` once the input is gone.

    End of input is end of file (Ctrl-D, a piped script that ends), a closed stdin, or a read
    that fails (a terminal that was closed reads EIO when the hang-up signal is ignored).
    """

    def __init__(self):
        self.ended = False

    def ask(self, prompt: str) -> str | None:
        """Prompt on stderr, read one line from stdin; None at end of input."""
        if self.ended:
            return None
        try:
            sys.stderr.write(prompt)
            sys.stderr.flush()
        except (OSError, ValueError):  # no terminal to prompt on: still read the answer
            pass
        try:
            line = sys.stdin.readline() if sys.stdin is not None else ""
        except (OSError, ValueError):  # EIO from a hung-up terminal, a closed file
            line = ""
        if not line:
            self.ended = True
            return None
        return line.strip()


class _HangUp(KeyboardInterrupt):
    """SIGHUP (the operator's terminal closed): stop like Ctrl-C, so everything is saved."""


def _hang_up(signum, frame):
    raise _HangUp()


def _say(err, text: str) -> None:
    """One line on stderr; silently nothing when stderr is gone (a closed terminal)."""
    try:
        err.print(text, soft_wrap=True)  # one line, however narrow the terminal
    except (OSError, ValueError):
        pass


def _numbers(text: str, count: int) -> list[float] | None:
    """Exactly ``count`` finite numbers typed on one line, or None when the line is not that."""
    import math

    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        return None
    if len(values) != count or not all(math.isfinite(v) for v in values):
        return None  # 'inf'/'nan' parse as floats but are no angle to aim at
    return values


def _aim_corner(ptu, label: str, ask):
    """Jog the head with 'pan tilt' (degrees) lines until 'ok'; return the unit angles (rad)."""
    import math

    from asbuilt.drivers.ptu import PTUError

    while True:
        pan, tilt = ptu.position()
        answer = ask(
            f"  {label}: head at pan {math.degrees(pan):.3f} tilt {math.degrees(tilt):.3f} deg; "
            "type 'PAN TILT' (deg) to move, 'ok' to take it: "
        )
        if answer is None:
            return None
        if answer.lower() in ("ok", "y", ""):
            return pan, tilt
        values = _numbers(answer, 2)
        if values is None:
            sys.stderr.write("  give two numbers PAN TILT (degrees), or 'ok' to take this corner\n")
            continue
        try:
            ptu.move_to(math.radians(values[0]), math.radians(values[1]))
        except PTUError as exc:
            sys.stderr.write(f"  {exc}\n")


def _laser(lrf, on: bool) -> None:
    """Laser pointer on/off while aiming, when the range finder has one (Dimetix)."""
    from asbuilt.errors import DeviceError

    switch = getattr(lrf, "laser", None)
    if switch is not None:
        try:
            switch(on)
        except DeviceError as exc:
            sys.stderr.write(f"  (laser pointer: {exc})\n")


def _interactive_targets(ptu, lrf, session, answers: _Input):
    """Prompt for targets until an empty id or end of input (``answers.ended``)."""
    from asbuilt.drivers.plan import Target, Window
    from asbuilt.errors import ScanError
    from asbuilt.scan.insulation import INSULATED_KINDS
    from asbuilt.scan.load import check_object_id, check_text
    from asbuilt.scan.model import KINDS

    ask = answers.ask
    while True:
        oid = ask("object id (empty to finish): ")
        if not oid:
            return
        try:
            check_object_id(oid, "id")
        except ScanError as exc:  # e.g. an arrow key's escape sequence typed into the id
            sys.stderr.write(f"  {exc.message}; choose another id\n")
            continue
        if session.is_done(oid):
            sys.stderr.write(f"  {oid} is already in the scan; choose another id\n")
            continue
        kind = ask(f"  kind ({'/'.join(KINDS)}): ")
        if kind is None:
            return
        if kind not in KINDS:
            sys.stderr.write(f"  unknown kind {kind!r}\n")
            continue
        text = ask("  window 'PAN1 TILT1 PAN2 TILT2' (deg) or 'aim': ")
        if text is None:
            return
        try:
            if text.lower() == "aim":
                _laser(lrf, True)
                try:
                    c1 = _aim_corner(ptu, "corner 1", ask)
                    c2 = _aim_corner(ptu, "corner 2", ask) if c1 is not None else None
                finally:
                    _laser(lrf, False)
                if c2 is None:
                    return
                window = Window.from_corners(c1[0], c1[1], c2[0], c2[1])
            else:
                corners = _numbers(text, 4)
                if corners is None:
                    sys.stderr.write(
                        "  give four numbers PAN1 TILT1 PAN2 TILT2 (degrees), or 'aim'\n"
                    )
                    continue
                window = Window.from_degrees(corners)
        except ValueError as exc:  # the two corners share a pan or a tilt angle
            sys.stderr.write(f"  bad window: {exc}\n")
            continue
        nominal = ask("  nominal size (optional): ")
        try:
            check_text(nominal or "", "nominal")
        except ScanError as exc:
            sys.stderr.write(f"  nominal size {exc.message}; give the object again\n")
            continue
        insulation = None
        if kind in INSULATED_KINDS:
            unit = _thickness_unit(session.units)
            typed = ask(f"  insulation thickness (optional, {unit}): ")
            problem, insulation = _typed_thickness(typed or "", unit)
            if problem is not None:
                sys.stderr.write(f"  insulation thickness {problem}; give the object again\n")
                continue
        yield Target(oid, kind, window, nominal=nominal or None, insulation=insulation)


def _thickness_unit(units: str) -> str:
    """The unit the operator types an insulation thickness in: inches in an imperial session
    (``--units in`` or ``ft``: lagging is sold in inches there), else millimetres."""
    return "in" if units in ("in", "ft") else "mm"


def _typed_thickness(text: str, unit: str) -> tuple[str | None, float | None]:
    """An answer to the insulation prompt: ``(None, metres)``, ``(None, None)`` when empty (a
    bare pipe), or ``(the problem, None)`` by the scan loader's rules (a number >= 0, at most
    :data:`~asbuilt.scan.insulation.MAX_INSULATION` once in metres)."""
    import math

    from asbuilt.scan.insulation import MAX_INSULATION
    from asbuilt.units import from_metres, to_metres

    if not text:
        return None, None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        return f"must be a number >= 0 in {unit}, not {text!r}", None
    metres = to_metres(value, unit)
    if metres > MAX_INSULATION:
        most = from_metres(MAX_INSULATION, unit)
        return (
            f"{value:g} {unit} is thicker than any pipe insulation (at most {most:g} {unit})",
            None,
        )
    return None, abs(metres)  # -0 typed is 0


def _check_plan_texts(plan, source: str) -> None:
    """Refuse, before the devices open, a plan whose targets the scan file could not carry: an
    id or text the scan loader refuses (a control character, white space at either end, more
    than 255 characters). The session would otherwise end in a scan file that no command
    reads. (An insulation thickness the loader would refuse is refused by
    :func:`~asbuilt.drivers.plan.load_plan` itself, by the same rules in metres.)"""
    from asbuilt.scan.load import check_object_id, check_text

    for index, target in enumerate(plan.targets):
        where = f"targets[{index}]"
        check_object_id(target.id, f"{where}.id", source=source)
        for field in ("group", "label", "nominal"):
            value = getattr(target, field, None)
            if isinstance(value, str):
                check_text(value, f"{where} ({target.id}).{field}", source=source)


def run(args: argparse.Namespace) -> int:
    """Open the devices, run the session, print a summary; see the module docstring."""
    from rich.console import Console

    from asbuilt.atomic import check_target
    from asbuilt.cli._args import refuse_other_format, refuse_standard_output
    from asbuilt.drivers.calibration import load_calibration
    from asbuilt.drivers.kinematics import Calibration
    from asbuilt.drivers.plan import load_plan
    from asbuilt.scan.load import check_text
    from asbuilt.units import unit_factor

    err = Console(stderr=True)
    _check_devices_options(args)
    _check_head_options(args)
    try:
        unit_factor(args.units)
    except ValueError as exc:
        from asbuilt.errors import ScanError

        raise ScanError(str(exc), where="--units") from None
    # The scan (and its journal beside it) must not replace the plan or the calibration it reads.
    refuse_standard_output(args.out, "--out", "the scan and its journal", "site.json")
    refuse_other_format(args.out, "--out", "an asbuilt-scan file", "site.json")
    check_target(
        args.out,
        "--out",
        inputs=[p for p in (args.plan, args.calibration) if p],
        example="site.json",
    )
    if args.name is not None:
        check_text(args.name, "--name")
    plan = load_plan(args.plan) if args.plan else None
    if plan is not None:
        _check_plan_texts(plan, args.plan)
    settings = _settings(args, plan)
    if args.resume:
        _check_resume_plan(args.out, plan, args.plan)
    if args.calibration:
        calibration = load_calibration(args.calibration)
    else:
        calibration = Calibration()  # said once the devices answer (a refused port: one line)

    hang_up = getattr(signal, "SIGHUP", None)  # POSIX: the operator's terminal closed
    previous = None
    if hang_up is not None and threading.current_thread() is threading.main_thread():
        previous = signal.signal(hang_up, _hang_up)
    try:
        return _run(args, err, settings, plan, calibration)
    finally:
        if previous is not None:
            signal.signal(hang_up, previous)


def _saved(session, out, why: str) -> str:
    """The one line saying what an ended or interrupted session saved and how to go on.

    The finished objects are written again first (each was written when it finished; this
    also covers an interruption during that write), so the file holds all of them.
    """
    if session.objects:
        session.write_scan()
        kept = f"{len(session.objects)} finished object(s) saved in {out}"
    else:
        kept = f"no finished object, so no {out}"
    return (
        f"{why}: {kept}; every shot is in {session.journal_path}; continue with asbuilt scan "
        "--resume (same --out)"
    )


def _check_resume_plan(out, plan, plan_file) -> None:
    """Refuse, before the devices open, a ``--resume`` with another plan than the journal's
    session (its targets would be appended to that session's scan); the session checks it
    again with the rest of the journal."""
    from pathlib import Path

    from asbuilt.drivers.journal import journal_path_for, read_journal
    from asbuilt.drivers.plan import resume_plan_mismatch
    from asbuilt.errors import ScanError

    journal = journal_path_for(out)
    if not journal.is_file() or journal.stat().st_size == 0:
        return  # the session says there is nothing to resume
    records = read_journal(journal)
    mismatch = resume_plan_mismatch(records, plan, plan_file and Path(plan_file).name)
    if mismatch:
        raise ScanError(mismatch, source=str(journal))


def _run(args, err, settings, plan, calibration) -> int:
    """The session proper (devices open to devices closed); see :func:`run`."""
    from rich.markup import escape
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn
    from rich.table import Table

    from asbuilt.drivers.ptu import open_pan_tilt_unit
    from asbuilt.drivers.rangefinder import open_range_finder
    from asbuilt.drivers.session import DeviceShooter, ScanSession
    from asbuilt.errors import DeviceError

    lrf_options = {}
    if args.lrf_baud:
        lrf_options["baudrate"] = args.lrf_baud
    if args.lrf_8n1 and args.lrf_protocol == "dimetix":
        lrf_options.update(bytesize=8, parity="N")
    if args.lrf_id is not None:
        lrf_options["device_id"] = args.lrf_id
    ptu = open_pan_tilt_unit(args.ptu, args.ptu_protocol, **_head_options(args))
    lrf = None
    session = None
    progress = Progress(
        TextColumn("{task.description}", markup=False),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("skipped {task.fields[skipped]}"),
        console=err,
        transient=False,
    )
    tasks: dict[str, int] = {}
    answers = _Input()
    ended = None  # the line to end with when the operator's input ended

    def on_shot(target, shot, taken, planned):
        if target.id not in tasks:
            tasks[target.id] = progress.add_task(
                f"{target.id} ({target.kind})", total=planned, skipped=0
            )
        task = tasks[target.id]
        skipped = progress.tasks[task].fields["skipped"] + (shot.range is None)
        progress.update(task, completed=taken, total=planned, skipped=skipped)

    def finish(object_id, result):
        if object_id in tasks:
            done = progress.tasks[tasks[object_id]].completed
            progress.update(tasks[object_id], total=done)
        if result is None:
            err.print(
                f"[red]{escape(f'{object_id}: ' + session.failed.get(object_id, 'failed'))}[/]"
            )

    try:
        lrf = open_range_finder(args.lrf, args.lrf_protocol, timeout=args.timeout, **lrf_options)
        probe = getattr(lrf, "probe", None)
        if probe is not None:
            probe()  # wrong line settings, id or cable: one error now, before the head moves
        if not args.calibration:
            err.print("[yellow]no --calibration: using an ideal chain at the origin[/]")
        shooter = DeviceShooter(ptu, lrf, settings)
        session = ScanSession(
            shooter,
            calibration,
            args.out,
            units=args.units,
            settings=settings,
            resume=args.resume,
            on_shot=on_shot,
            name=args.name,
            plan=plan,
            plan_file=args.plan,
        )
        with progress:
            if session.pending is not None:
                err.print(f"resuming {escape(session.pending.id)} from the journal")
                finish(session.pending.id, session.scan(session.pending))
            if plan is not None:
                targets = plan.targets
            else:
                targets = _interactive_targets(ptu, lrf, session, answers)
            for target in targets:
                if session.is_done(target.id):
                    continue
                finish(target.id, session.scan(target))
        if answers.ended:
            ended = _saved(session, args.out, "end of input")
    except KeyboardInterrupt as exc:
        if session is None:
            _say(err, "stopped before the session started; nothing new to save")
        else:
            what = "hang-up" if isinstance(exc, _HangUp) else "stopped"
            _say(err, escape(_saved(session, args.out, what)))
        return 130
    except DeviceError as exc:
        if session is None:
            raise
        # The session's own "lost" errors already say to resume: the hint once.
        resume = "" if "--resume" in str(exc) else "; continue with asbuilt scan --resume"
        raise DeviceError(
            f"{exc} (every shot so far is in {session.journal_path}{resume})"
        ) from None
    finally:
        if session is not None:
            session.close()
        if lrf is not None:
            lrf.close()
        ptu.close()

    table = Table(title=f"scan {escape(str(args.out))}")
    for col in ("id", "kind", "points", "shots", "skipped", "background"):
        table.add_column(col, justify="left" if col in ("id", "kind") else "right")
    for result in session.objects.values():
        n = int(result.on_object.sum())
        background = sum(
            1 for s, on in zip(result.shots, result.on_object) if s.range is not None and not on
        )
        table.add_row(
            escape(result.target.id),
            result.target.kind,
            str(n),
            str(len(result.shots)),
            str(result.skipped),
            str(background),
        )
    err.print(table)
    for oid, reason in session.failed.items():
        err.print(f"[red]{escape(f'{oid}: not in the scan: {reason}')}[/]")
    if ended is not None:
        _say(err, escape(ended))
    return 1 if session.failed else 0
