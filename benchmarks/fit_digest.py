"""Regression digest of fit outputs: which fits a change of the fitting code changed, and
whether they got better or worse against the truth.

Three steps, each a subcommand::

    python benchmarks/fit_digest.py sets SETS.npz [--scale S] [--sources A,B]
    python benchmarks/fit_digest.py run SETS.npz OUT.json [--repo PATH] [--jobs N] [--only KIND,...]
    python benchmarks/fit_digest.py diff A.json B.json [--show N]

``sets`` draws the point sets once, with fixed seeds, from the benchmarks' own generators
(``benchmarks/digest_sets.py`` lists them); they do not depend on the code under test once
drawn. ``run`` fits every set with the ``asbuilt`` of ``--repo`` (default: this checkout) in
``--jobs`` worker processes, each with that repository first on ``sys.path``, and writes every
fit's outcome: the parameters as exact float ``repr`` strings, or the refusal's exception class
and message; with the repository's commit and dirty state and a digest hash over all records.
``diff`` compares two runs of the same sets: see ``benchmarks/digest_diff.py``.

Typical use before merging a fitting change (both runs on the same sets file)::

    python benchmarks/fit_digest.py sets /tmp/sets.npz
    git worktree add /tmp/base main
    python benchmarks/fit_digest.py run /tmp/sets.npz /tmp/base.json --repo /tmp/base
    python benchmarks/fit_digest.py run /tmp/sets.npz /tmp/new.json
    python benchmarks/fit_digest.py diff /tmp/base.json /tmp/new.json

Metres inside; the records are in metres and degrees as the fits return them.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import multiprocessing
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import digest_sets  # noqa: E402 (numpy and the standard library only: no asbuilt)

FORMAT = "asbuilt-fit-digest"
KINDS = ("cylinder", "cuboid", "sphere", "plane", "auto")
#: Record fields that are not the fit's outcome (left out of the comparison and the hash):
#: the fit's time and the set's truth.
UNCOMPARED = ("seconds", "truth")

# --------------------------------------------------------------------------- worker side

_STATE: dict = {}


def _init_worker(repo: str, sets_path: str) -> None:
    """Pool initializer: ``repo`` first on ``sys.path``, then the sets loaded once."""
    sys.path.insert(0, repo)
    _, entries, points, offsets = digest_sets.load(sets_path)
    _STATE.update(repo=repo, entries=entries, points=points, offsets=offsets)


def _reprs(value):
    """Exact ``repr`` strings of a float or of nested arrays of them."""
    if np.ndim(value) == 0:
        return repr(float(value))
    return [_reprs(v) for v in np.asarray(value, dtype=np.float64)]


def _params(primitive) -> dict:
    """The fitted primitive's parameters (metres, unit vectors) as exact repr strings."""
    kind = primitive.kind
    if kind == "cylinder":
        names = ("radius", "center", "axis", "length")
    elif kind == "sphere":
        names = ("center", "radius")
    elif kind == "plane":
        names = ("point", "normal", "outline")
    elif kind == "cuboid":
        names = ("center", "axes", "size")
    else:  # a hull: its vertices
        names = ("vertices",)
    params = {}
    for name in names:
        value = getattr(primitive, name)
        if value is not None:
            params[name] = _reprs(value)
    return params


def _outcome(result, fused_with=None) -> dict:
    """The record fields of one fit result."""
    record = {
        "status": "fit",
        "fitted": result.primitive.kind,
        "params": _params(result.primitive),
        "n_inliers": result.n_inliers,
        "stderr": {k: _reprs(v) for k, v in sorted(result.stderr.items())},
        "sigma": _reprs(result.sigma),
        "sigma_source": result.sigma_source,
        "method": result.method,
        "notes": len(result.notes),
    }
    if result.observed is not None:
        record["params"]["observed"] = [bool(o) for o in result.observed]
    if fused_with is not None:
        record["fused_with"] = fused_with
    return record


def _fit_scan(entry):
    """The scan document's fit of ``entry["object"]`` through :func:`asbuilt.fit.fit`."""
    from asbuilt.errors import FitError
    from asbuilt.fit import fit
    from asbuilt.scan import loads_scan

    report = fit(loads_scan(json.dumps(entry["scan"]), source="digest.json"))
    for item in report.fits:
        if item.object.id == entry["object"]:
            return item.result, item.object.extra.get("fused_with")
    for failure in report.failures:
        if failure.object.id == entry["object"]:
            raise failure.error
    raise FitError(f"no fit of {entry['object']} in the report")


def fit_set(index: int) -> dict:
    """Fit set ``index`` of the loaded sets: its record (see :func:`_outcome`)."""
    entry = _STATE["entries"][index]
    offsets = _STATE["offsets"]
    points = _STATE["points"][offsets[index] : offsets[index + 1]]
    options = {}
    if entry["sigma"] is not None:
        options["sigma"] = entry["sigma"]
    if entry["viewpoint"] is not None:
        options["viewpoint"] = np.array(entry["viewpoint"])
    record = {"key": entry["key"], "kind": entry["kind"]}
    started = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fused = None
            if entry["call"] == "fit_points":
                from asbuilt.fit import fit_points

                result = fit_points(entry["kind"], points, **options)
            elif entry["call"] == "fit_auto":
                from asbuilt.fit.auto import fit_auto

                result = fit_auto(points, **options)
            else:
                result, fused = _fit_scan(entry)
        record.update(_outcome(result, fused))
    except Exception as exc:  # every refusal and every crash is an outcome
        message = getattr(exc, "message", None) or str(exc)
        record.update(status="refused", error=f"{type(exc).__name__}: {message[:80]}")
    record["seconds"] = round(time.perf_counter() - started, 6)
    record["truth"] = entry["truth"]  # input, not outcome: for the diff's errors
    return record


def fit_chunk(indices: list[int]) -> list[dict]:
    """Records of the sets ``indices``, after checking which asbuilt this worker imports."""
    import asbuilt

    where = Path(asbuilt.__file__).resolve()
    if Path(_STATE["repo"]).resolve() not in where.parents:
        raise RuntimeError(f"worker imported asbuilt from {where}, not from {_STATE['repo']}")
    return [fit_set(i) for i in indices]


# --------------------------------------------------------------------------- main side


def digest_hash(records: list[dict]) -> str:
    """SHA-256 over every record's outcome (its time left out), in key order."""
    digest = hashlib.sha256()
    for record in sorted(records, key=lambda r: r["key"]):
        kept = {k: v for k, v in record.items() if k not in UNCOMPARED}
        digest.update(json.dumps(kept, sort_keys=True).encode())
        digest.update(b"\n")
    return digest.hexdigest()


def _asbuilt_file(repo: Path) -> str:
    """Where a fresh interpreter with ``repo`` first on its path imports asbuilt from."""
    code = f"import sys; sys.path.insert(0, {str(repo)!r}); import asbuilt; print(asbuilt.__file__)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"fit_digest: cannot import asbuilt from {repo}: {done.stderr.strip()}")
    where = Path(done.stdout.strip()).resolve()
    if repo.resolve() not in where.parents:
        raise SystemExit(f"fit_digest: {repo} has no asbuilt package of its own (got {where})")
    return str(where)


def write_run(path: Path, header: dict, records: list[dict]) -> None:
    """The run as JSON, one record a line (readable with ``diff`` and ``grep``)."""
    head = json.dumps(header, indent=1)[:-2]  # open: the records follow
    lines = ",\n".join(json.dumps(r, sort_keys=True) for r in records)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(f'{head},\n "records": [\n{lines}\n ]\n}}\n')
    os.replace(tmp, path)


@contextlib.contextmanager
def _one_thread_each():
    """Workers started within get one BLAS thread each: the workers are the parallelism, and
    threads would make floating-point sums depend on the machine's load."""
    names = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    before = {name: os.environ.get(name) for name in names}
    os.environ.update(dict.fromkeys(names, "1"))
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _versions() -> dict:
    """Python's and the numerical libraries' versions (a fit's last bits depend on them)."""
    from importlib import metadata

    found = {"python": sys.version.split()[0]}
    for name in ("numpy", "scipy"):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return found


def run(sets_path, out_path, repo=None, jobs=2, only=None, chunk=8, log=sys.stderr) -> dict:
    """Fit every set (of the kinds ``only``) and write the run; returns its header."""
    repo = Path(repo) if repo is not None else HERE.parent
    meta, entries, _, offsets = digest_sets.load(sets_path)
    wanted = [i for i, e in enumerate(entries) if only is None or e["kind"] in only]
    # The slow fits first (auto fits every kind; dense sets), so that no worker is left with
    # a long one at the end while the other idles; the records keep the sets' order.
    sizes = np.diff(offsets)
    slow = sorted(
        (i for i in wanted if entries[i]["kind"] == "auto" or sizes[i] > 200),
        key=lambda i: -sizes[i],
    )
    order = slow + sorted(set(wanted) - set(slow))
    asbuilt_file = _asbuilt_file(repo)
    started = time.perf_counter()
    records = []
    chunks = [order[k : k + chunk] for k in range(0, len(order), chunk)]
    context = multiprocessing.get_context("spawn")  # nothing imported here leaks into them
    with _one_thread_each(), context.Pool(jobs, _init_worker, (str(repo), str(sets_path))) as pool:
        step = max(1, len(chunks) // 10)
        for k, got in enumerate(pool.imap_unordered(fit_chunk, chunks)):
            records.extend(got)
            if log is not None and (k + 1) % step == 0:
                print(
                    f"  {len(records)}/{len(wanted)} sets, {time.perf_counter() - started:.0f} s",
                    file=log,
                    flush=True,
                )
    elapsed = time.perf_counter() - started
    position = {entries[i]["key"]: i for i in wanted}
    records.sort(key=lambda r: position[r["key"]])
    header = {
        "format": FORMAT,
        "version": 1,
        "repo": str(repo.resolve()),
        **digest_sets.git_state(repo),
        "asbuilt": asbuilt_file,
        "versions": _versions(),
        "sets_file": str(sets_path),
        "sets_sha256": meta["sha256"],
        "sets_scale": meta.get("scale"),
        "only": None if only is None else sorted(only),
        "jobs": jobs,
        "wall_seconds": round(elapsed, 1),
        "records_count": len(records),
        "refused": sum(r["status"] == "refused" for r in records),
        "digest": digest_hash(records),
    }
    write_run(Path(out_path), header, records)
    return header


def load_run(path) -> dict:
    data = json.loads(Path(path).read_text())
    if data.get("format") != FORMAT:
        raise SystemExit(f"fit_digest: {path} is not a fit digest run")
    return data


# --------------------------------------------------------------------------- CLI


def _cmd_sets(args) -> int:
    sources = digest_sets.SOURCES if args.sources is None else tuple(args.sources.split(","))
    unknown = set(sources) - set(digest_sets.SOURCES)
    if unknown:
        raise SystemExit(
            f"fit_digest: unknown sources {sorted(unknown)}; known: {digest_sets.SOURCES}"
        )
    started = time.perf_counter()

    def progress(source, count, seconds):
        print(f"  {source}: {count} sets ({seconds:.0f} s)", file=sys.stderr, flush=True)

    drawn = digest_sets.draw(args.scale, sources, progress)
    meta = digest_sets.save(
        drawn,
        Path(args.sets),
        {
            "scale": args.scale,
            "sources": list(sources),
            "generator": digest_sets.git_state(HERE.parent),
            "seconds": round(time.perf_counter() - started, 1),
        },
    )
    print(f"{args.sets}: {meta['sets']} sets in {meta['seconds']} s (sha256 {meta['sha256'][:16]})")
    totals: dict = {}
    for source, kinds in meta["counts"].items():
        text = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items()))
        print(f"  {source}: {text}")
        for kind, n in kinds.items():
            totals[kind] = totals.get(kind, 0) + n
    print("  all: " + ", ".join(f"{n} {k}" for k, n in sorted(totals.items())))
    return 0


def _cmd_run(args) -> int:
    only = None
    if args.only:
        only = set(args.only.split(","))
        if only - set(KINDS):
            raise SystemExit(f"fit_digest: --only takes kinds among {', '.join(KINDS)}")
    header = run(args.sets, args.out, repo=args.repo, jobs=args.jobs, only=only)
    state = "dirty" if header["dirty"] else "clean"
    print(
        f"{args.out}: {header['records_count']} fits ({header['refused']} refused) of "
        f"{header['repo']} at {str(header['commit'])[:12]} ({state}), {header['jobs']} jobs, "
        f"{header['wall_seconds']} s; digest {header['digest'][:16]}"
    )
    return 0


def _cmd_diff(args) -> int:
    import digest_diff

    print(digest_diff.report(load_run(args.a), load_run(args.b), show=args.show), end="")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    sets = commands.add_parser("sets", help="draw the point sets (fixed seeds) into SETS.npz")
    sets.add_argument("sets", help="output .npz")
    sets.add_argument("--scale", type=float, default=1.0, help="trials per cell x S (1)")
    sets.add_argument(
        "--sources", help="comma-separated sources (default all): " + ",".join(digest_sets.SOURCES)
    )
    sets.set_defaults(handler=_cmd_sets)
    runs = commands.add_parser("run", help="fit every set and write the records")
    runs.add_argument("sets", help="a file written by `sets`")
    runs.add_argument("out", help="output .json")
    runs.add_argument("--repo", help="the checkout whose asbuilt fits (default: this one)")
    runs.add_argument("--jobs", type=int, default=2, help="worker processes (2)")
    runs.add_argument("--only", help="comma-separated kinds asked: " + ",".join(KINDS))
    runs.set_defaults(handler=_cmd_run)
    diff = commands.add_parser("diff", help="compare two runs of the same sets (exit 0)")
    diff.add_argument("a", help="the run before (e.g. main)")
    diff.add_argument("b", help="the run after (e.g. the branch)")
    diff.add_argument("--show", type=int, default=15, help="list this many of each (15)")
    diff.set_defaults(handler=_cmd_diff)
    args = parser.parse_args(argv)
    return args.handler(args)


if __name__ == "__main__":
    raise SystemExit(main())
