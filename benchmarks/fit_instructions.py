"""Instructions per fit (valgrind callgrind), on the trials ``cylinder_speed.py`` and
``cuboid_speed.py`` time.

Wall-clock time on a shared virtual machine wanders by up to 2x from one minute to the next,
so a 10% change cannot be seen in it. The instructions a fit executes do not wander: this
script runs the same fit calls as the speed scripts under valgrind's callgrind, which dumps its
counts each time a marker function (``os.getppid``, called between fits) is entered, and
reports the median and mean instructions per fit. Two revisions compared this way differ by
what their code does, not by the machine's phase. (Instructions are not time: numpy's memory
traffic and Python's allocations weigh differently, so compare revisions with it, and quote
times measured in a quiet phase.)

Run: ``python benchmarks/fit_instructions.py --kind cuboid --data dirty --viewpoint station``
(needs ``valgrind``; about 5 minutes for 300 fits). ``--inner`` is the process valgrind runs.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _fit_all(args) -> None:
    """The fits, each preceded by the marker call (run under valgrind)."""
    sys.path.insert(0, str(HERE))
    sys.path.insert(0, str(HERE.parent))
    import cuboid_speed
    import cylinder_speed
    import fit_accuracy

    from asbuilt.fit import fit_points

    module = cuboid_speed if args.kind == "cuboid" else cylinder_speed
    data = module.trials(args.points, args.trials, args.seed)
    scans = [getattr(trial, args.data) for trial in data]
    viewpoint = fit_accuracy.STATION.position if args.viewpoint == "station" else None

    def fit(points) -> None:
        try:
            fit_points(args.kind, points, sigma=fit_accuracy.SIGMA_R, viewpoint=viewpoint)
        except Exception:  # a failed fit counts too, as in the speed scripts
            pass

    for points in scans[:5]:  # imports and first-call caches, outside the counts
        fit(points)
    for points in scans:
        os.getppid()
        fit(points)
    os.getppid()


def _counts(directory: Path) -> list[int]:
    """Instructions of each fit from callgrind's numbered dumps (dump k + 1 holds fit k)."""
    dumps = []
    for path in directory.glob("callgrind.out.*"):
        number = re.search(r"\.(\d+)$", path.name)
        if number is None:
            continue
        total = None
        for line in path.read_text().splitlines():
            if line.startswith(("summary:", "totals:")):
                total = int(line.split()[1])
        dumps.append((int(number.group(1)), total))
    dumps.sort()
    return [total for _, total in dumps[1:] if total is not None]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", choices=("cylinder", "cuboid"), default="cuboid")
    parser.add_argument("--data", choices=("clean", "dirty"), default="dirty")
    parser.add_argument("--viewpoint", choices=("station", "none"), default="station")
    parser.add_argument("--points", type=int, default=40)
    parser.add_argument("--trials", type=int, default=50, help="trials per cell (50)")
    parser.add_argument("--seed", type=int, default=2004)
    parser.add_argument(
        "--counts-out", type=Path, help="also write each fit's instructions (one per line)"
    )
    parser.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.inner:
        _fit_all(args)
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed (Debian: apt install valgrind)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        command = [
            "valgrind",
            "--tool=callgrind",
            "--dump-before=getppid",
            f"--callgrind-out-file={out / 'callgrind.out'}",
            sys.executable,
            str(Path(__file__).resolve()),
            "--inner",
            *(argv if argv is not None else sys.argv[1:]),
        ]
        env = dict(os.environ, PYTHONHASHSEED="0")
        subprocess.run(command, check=True, env=env, capture_output=True)
        counts = _counts(out)
    millions = [count / 1e6 for count in counts]
    if args.counts_out is not None:
        args.counts_out.write_text("".join(f"{count}\n" for count in counts))
    print(
        f"{args.kind}, {args.data}, viewpoint {args.viewpoint}: {len(millions)} fits, "
        f"median {statistics.median(millions):.2f} M instructions, "
        f"mean {statistics.mean(millions):.2f} M"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
