"""Exports chosen by the output's suffix: STEP, glTF, DXF, STL, OBJ, PCF, IFC and the JSON
model document.

``export_models(model, paths)`` writes several outputs in one run: every suffix is checked
first, the solids are built once (only if a CAD format is asked for) and shared, every file is
written to a temporary file beside its target, and all are renamed into place only when all
succeeded (:class:`asbuilt.atomic.AtomicBatch`). Importing this package does not load CadQuery;
the format modules are imported when used.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path

from asbuilt.atomic import AtomicBatch, default_file_mode
from asbuilt.errors import AsbuiltError, ExportError, UnknownFormatError

__all__ = [
    "SUFFIXES",
    "Exporter",
    "ExportResult",
    "exporter_for",
    "export_model",
    "export_models",
]


@dataclass(frozen=True)
class Exporter:
    """One output format: ``suffix`` (``".step"``), ``name`` (``"STEP"``), a description,
    whether it needs the CAD model (``needs_cad``: a :class:`asbuilt.cad.CadModel`, else the
    model itself), where its writer lives (module, function), and whether it needs the B-rep
    solids (``needs_solids``; the others use only the parts' meshes)."""

    suffix: str
    name: str
    description: str
    needs_cad: bool
    module: str
    function: str
    needs_solids: bool = False

    def write(self, source, path, **options) -> None:
        """Write ``source`` (a CadModel when ``needs_cad``, else a Model) to ``path``."""
        writer = getattr(import_module(f"{__name__}.{self.module}"), self.function)
        writer(source, path, **options)


_EXPORTERS = (
    Exporter(
        ".step",
        "STEP",
        "STEP AP214 assembly, millimetres, names and colours",
        True,
        "step",
        "write_step",
        True,
    ),
    Exporter(
        ".stp",
        "STEP",
        "STEP AP214 assembly, millimetres, names and colours",
        True,
        "step",
        "write_step",
        True,
    ),
    Exporter(".glb", "glTF", "binary glTF 2.0, metres, Y up", True, "gltf", "write_gltf"),
    Exporter(
        ".gltf",
        "glTF",
        "glTF 2.0 JSON with embedded buffer, metres, Y up",
        True,
        "gltf",
        "write_gltf",
    ),
    Exporter(
        ".dxf",
        "DXF",
        "DXF R2018 meshes with plan and elevation views, millimetres",
        True,
        "dxf",
        "write_dxf",
    ),
    Exporter(".stl", "STL", "binary STL mesh in the model's units", True, "mesh", "write_stl"),
    Exporter(
        ".obj",
        "OBJ",
        "Wavefront OBJ, one object per component, model's units",
        True,
        "mesh",
        "write_obj",
    ),
    Exporter(
        ".pcf",
        "PCF",
        "ISOGEN piping component file (piping only), millimetres",
        False,
        "pcf",
        "write_pcf",
    ),
    Exporter(
        ".ifc",
        "IFC",
        "IFC4 pipe segments, fittings and building elements, metres (needs ifcopenshell)",
        False,
        "ifc",
        "write_ifc",
    ),
    Exporter(
        ".json",
        "JSON",
        "the asbuilt-model document (metres)",
        False,
        "model_json",
        "_write_document",
    ),
)

#: Every suffix an output may have, mapped to its exporter.
SUFFIXES: dict[str, Exporter] = {exporter.suffix: exporter for exporter in _EXPORTERS}


def exporter_for(path) -> Exporter:
    """The exporter for ``path``'s suffix (case-insensitive).

    Raises
    ------
    UnknownFormatError
        Naming the file and the suffixes that are known.
    """
    suffix = Path(path).suffix.lower()
    try:
        return SUFFIXES[suffix]
    except KeyError:
        known = ", ".join(SUFFIXES)
        what = f"unknown output format {suffix!r}" if suffix else "the output has no suffix"
        raise UnknownFormatError(f"{what}; use one of {known}", source=str(path)) from None


@dataclass(frozen=True)
class ExportResult:
    """A file written: its ``path``, format ``name``, ``size`` in bytes and ``objects`` count."""

    path: Path
    name: str
    size: int
    objects: int


def _writer_options(
    exporter: Exporter,
    target: Path,
    step_schema: str,
    mesh_units: str | None,
    plate_thickness: float | None = None,
) -> dict:
    if exporter.module == "step":
        return {"schema": step_schema, "file_name": target.name}
    if exporter.module == "gltf":
        return {"binary": exporter.suffix == ".glb"}
    if exporter.module == "mesh" and mesh_units is not None:
        return {"units": mesh_units}
    if exporter.module == "ifc":
        return {"plate_thickness": plate_thickness}
    return {}


@contextlib.contextmanager
def _sigterm_deferred() -> Iterator[None]:
    """Hold back SIGTERM and SIGINT (Ctrl-C) until the block ends, then deliver each to the
    handler there was.

    For imports of the CAD kernel (CadQuery, OCP, VTK: seconds): an exception raised by a
    handler in the middle of an extension module's initialisation left it half made: the
    process crashed (exit 139) on SIGTERM, and Ctrl-C surfaced as OCP's ImportError
    ("initialization failed"). A SIGINT the caller ignores stays ignored.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []

    def hold(signum, frame):
        pending.append(signum)

    held = [signal.SIGTERM]
    if signal.getsignal(signal.SIGINT) not in (signal.SIG_IGN, None):
        held.append(signal.SIGINT)
    previous = {signum: signal.signal(signum, hold) for signum in held}
    try:
        yield
    finally:
        # None: a handler installed outside Python, which cannot be put back; the default then.
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        # SIGTERM first: of the two requests to stop it is the stronger, and the first
        # delivered may end the run with its exception
        for signum in held:
            if signum in pending:
                signal.raise_signal(signum)


def _load_writers(exporters: Sequence[Exporter]) -> None:
    """Import the CAD layer (when a format needs solids) and every writer's module.

    Done before any file is staged, with SIGTERM and SIGINT held back
    (:func:`_sigterm_deferred`): a kill or Ctrl-C during these imports then stops the run
    cleanly, after them and before it has created anything. An optional
    package a writer lacks (ifcopenshell) is reported by that writer, as before.
    """
    with _sigterm_deferred():
        if any(exporter.needs_cad for exporter in exporters):
            import_module("asbuilt.cad")
        for exporter in exporters:
            import_module(f"{__name__}.{exporter.module}")


def export_models(
    model,
    paths: Iterable,
    *,
    cad=None,
    plate_thickness: float | None = None,
    step_schema: str = "AP214",
    mesh_units: str | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    batch: AtomicBatch | None = None,
) -> list[ExportResult]:
    """Write ``model`` to every path, all or nothing.

    Parameters
    ----------
    model : asbuilt.model.Model
        Metres, scan frame.
    paths : iterable of str or Path
        Outputs; each suffix picks the format (:data:`SUFFIXES`).
    cad : asbuilt.cad.CadModel, optional
        Solids already built for ``model`` (built here when a CAD format needs them).
    plate_thickness : float, metres, optional
        Thickness of plates made from planes (default ``Tolerances.plate_thickness``).
    step_schema : {"AP214", "AP242"}
    mesh_units : str, optional
        Unit for STL/OBJ coordinates (default the model's ``units``).
    progress : callable(task, done, total), optional
        Told about solids built (``"solids"``) and files written (``"files"``).
    batch : asbuilt.atomic.AtomicBatch, optional
        Stage the files in this batch and leave publishing them to its owner (with other
        outputs of the same run, such as reports: all or nothing together).

    Returns
    -------
    list of ExportResult
        In the order of ``paths``.

    Raises
    ------
    UnknownFormatError, ExportError, SolidBuildError
        Before anything is renamed into place: no output is created or replaced on failure.
    """
    targets = [Path(p) for p in paths]
    exporters = [exporter_for(p) for p in targets]
    seen: set[Path] = set()
    for target in targets:
        key = target.resolve()
        if key in seen:
            raise ExportError(
                "this output is given twice; name each output once", source=str(target)
            )
        seen.add(key)
    if not model.components:
        for exporter, target in zip(exporters, targets):
            if exporter.needs_cad:
                raise ExportError(
                    f"the model has no objects, so there is no {exporter.name} geometry to "
                    "write; check that the scan has objects",
                    source=str(target),
                )
    _load_writers(exporters)
    mode = default_file_mode()
    sizes = []
    with contextlib.nullcontext(batch) if batch is not None else AtomicBatch() as batch:
        temps = [batch.stage(target) for target in targets]
        if cad is None and any(exporter.needs_cad for exporter in exporters):
            from asbuilt.cad import prepare

            def solids_progress(done: int, total: int) -> None:
                if progress is not None:
                    progress("solids", done, total)

            # Mesh formats alone need no B-rep solids (a dense hull's takes minutes to sew).
            cad = prepare(
                model,
                plate_thickness=plate_thickness,
                progress=solids_progress,
                solids=any(exporter.needs_solids for exporter in exporters),
            )
        for done, (exporter, temp, target) in enumerate(zip(exporters, temps, targets), 1):
            options = _writer_options(exporter, target, step_schema, mesh_units, plate_thickness)
            try:
                exporter.write(cad if exporter.needs_cad else model, temp, **options)
            except AsbuiltError as exc:
                if getattr(exc, "source", None) in (None, str(temp)) and isinstance(
                    exc, ExportError
                ):
                    raise type(exc)(exc.message, source=str(target), where=exc.where) from None
                raise
            except OSError as exc:
                raise ExportError(
                    f"cannot write the file ({exc.strerror or exc})", source=str(target)
                ) from None
            os.chmod(temp, mode)
            sizes.append(temp.stat().st_size)
            if progress is not None:
                progress("files", done, len(targets))
    count = len(model.components)
    return [
        ExportResult(target, exporter.name, size, count)
        for exporter, target, size in zip(exporters, targets, sizes)
    ]


def export_model(model, path, **options) -> ExportResult:
    """Write ``model`` to one ``path`` (format by suffix), atomically; see :func:`export_models`
    for the options."""
    return export_models(model, [path], **options)[0]


def formats_table() -> Sequence[tuple[str, str, str]]:
    """``(suffix, format name, description)`` for every known suffix (for help texts)."""
    return [(e.suffix, e.name, e.description) for e in _EXPORTERS]
