"""The ``SCAN`` argument every command that reads a scan shares: a file, or ``-`` for standard
input.

``asbuilt fit - < scan.json`` (and ``model``, ``check``, ``report``, ``calibrate``) reads the scan
from standard input, up to the loader's size limit (:data:`asbuilt.scan.load.MAX_FILE_BYTES`).
A bad scan is refused as a bad file is: one line, naming ``<stdin>`` instead of the path, and
the place and field (``<stdin>: objects[0] (P1).points: ...``), exit code 2, nothing written.
Where a command also takes an ``asbuilt-model`` document (``check``, ``report``), one piped in
is recognised as a file is.
"""

from __future__ import annotations

__all__ = ["STDIN", "STDIN_NAME", "SCAN_HELP", "ScanInput", "input_files", "scan_input"]

#: The ``SCAN`` argument that means standard input.
STDIN = "-"
#: How messages name standard input (the source of its scan or model).
STDIN_NAME = "<stdin>"
#: The phrase every ``SCAN`` help text ends with.
SCAN_HELP = "'-': read it from standard input"


class ScanInput:
    """A ``SCAN`` argument: a path, or standard input's bytes read once.

    Parameters
    ----------
    path : str
        The argument as given (``"-"`` for standard input).
    data : bytes, optional
        Standard input's bytes (None for a file).

    Attributes
    ----------
    name : str
        How messages name the input: the path as given, or ``<stdin>``.
    """

    def __init__(self, path: str, data: bytes | None = None):
        self.path = path
        self.data = data
        self.name = STDIN_NAME if data is not None else str(path)

    def is_model(self) -> bool:
        """Whether the input is an ``asbuilt-model`` document rather than a scan (False for
        anything unreadable or not JSON: the scan loader then reports the problem)."""
        from asbuilt.export.model_json import is_model_document

        if self.data is None:
            return is_model_document(self.path)
        return self._model_document() is not None

    def load_scan(self):
        """The validated :class:`~asbuilt.scan.Scan` (ScanError or ScanReadError, exit 2)."""
        from asbuilt.scan import load_scan, loads_scan

        if self.data is None:
            return load_scan(self.path)
        return loads_scan(self.data, source=STDIN_NAME)

    def load_model(self):
        """The :class:`~asbuilt.model.Model` of an ``asbuilt-model`` document
        (ModelDocumentError, exit 2, naming the component and field)."""
        from asbuilt.export.model_json import load_model, model_from_document

        if self.data is None:
            return load_model(self.path)
        document = self._model_document()
        if document is None:  # callers ask is_model() first; this is the message if not
            from asbuilt.export.model_json import ModelDocumentError

            raise ModelDocumentError(
                "is not an asbuilt-model document (its format is not 'asbuilt-model')",
                source=STDIN_NAME,
            )
        # Read again as a file is (a key given twice refused): recognising it was lenient.
        from asbuilt.export.model_json import loads_model_document

        document = loads_model_document(self.data.decode("utf-8-sig"), source=STDIN_NAME)
        return model_from_document(document, source=STDIN_NAME)

    def _model_document(self):
        """Standard input's JSON object when it is an ``asbuilt-model`` document, else None
        (recognised as :func:`asbuilt.export.model_json.is_model_document` does a file)."""
        from asbuilt.export.model_json import model_document_in

        return model_document_in(self.data)


def _standard_input() -> bytes:
    """Standard input's bytes, refused past the loader's size limit (one byte beyond it is read,
    not the rest of an endless stream), when closed, or when it is a terminal (nothing piped)."""
    import sys

    from asbuilt.errors import ScanReadError
    from asbuilt.scan.load import MAX_FILE_BYTES

    stream = getattr(sys.stdin, "buffer", None)
    if stream is None or sys.stdin.closed:
        raise ScanReadError(
            f"{STDIN_NAME}: standard input is closed; pipe the scan in (... | asbuilt fit -) "
            "or give its file"
        )
    try:
        interactive = sys.stdin.isatty()
    except (OSError, ValueError):
        interactive = False
    if interactive:
        raise ScanReadError(
            f"{STDIN_NAME}: standard input is a terminal, not a scan; pipe the scan in "
            "(... | asbuilt fit -) or give its file"
        )
    try:
        data = stream.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ScanReadError(f"{STDIN_NAME}: cannot be read ({exc.strerror})") from None
    if len(data) > MAX_FILE_BYTES:
        raise ScanReadError(
            f"{STDIN_NAME}: holds more than {MAX_FILE_BYTES // (1024 * 1024)} MiB, too large "
            "for a sparse scan; split it into several scans"
        )
    return data


def input_files(path, *others) -> list:
    """The input files a command reads, which an output must not replace
    (:func:`asbuilt.atomic.check_target`): the ``SCAN`` argument (none for standard input,
    whatever file is named ``-``) and ``others``, the files of options such as ``--rules``,
    ``--design``, ``--catalog`` (None when not given; a catalog name names no file and never
    matches)."""
    return [p for p in (None if path == STDIN else path, *others) if p is not None]


def scan_input(path: str) -> ScanInput:
    """The :class:`ScanInput` of a ``SCAN`` argument; ``-`` reads standard input now (call it
    after the cheap option checks, before the work).

    Raises
    ------
    ScanReadError
        Standard input is closed, a terminal, unreadable or too large (one line, exit 2).
    """
    if path == STDIN:
        return ScanInput(path, _standard_input())
    return ScanInput(path)
