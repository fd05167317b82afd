"""Reading a user's text file (design, model, scene, rules, catalog, calibration, plan) the same
way everywhere: UTF-8 with or without a byte order mark, and one located line naming the file and
what to do when it is missing, a directory, unreadable or not UTF-8.

The scan loader (:mod:`asbuilt.scan.load`) opens its file itself (a size limit, standard input)
and decodes it with :func:`decode_text`.
"""

from __future__ import annotations

import json
import os

from asbuilt._json_numbers import parse_int

__all__ = ["REPEATED_KEY", "RepeatedKey", "decode_text", "loads_json", "read_text", "unique_keys"]

#: The message for a key given twice in one JSON object (every reader refuses it, located at
#: the key).
REPEATED_KEY = "given twice in one JSON object; keep one (JSON readers differ on which one counts)"


class RepeatedKey(ValueError):
    """A key given twice in one JSON object (``args[0]``: the key)."""


def unique_keys(pairs: list) -> dict:
    """``json.loads`` ``object_pairs_hook``: a dict, refusing a key given twice (raises
    :class:`RepeatedKey`; catch it before ``ValueError``, which JSONDecodeError also is)."""
    result = dict(pairs)
    if len(result) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise RepeatedKey(key)
            seen.add(key)
    return result


def loads_json(text: str, error, *, source: str | None):
    """``json.loads`` of a user's file as every reader parses it: a too-long integer reads as
    infinite (refused by its field's name, :func:`asbuilt._json_numbers.parse_int`), and a key
    given twice raises ``error(REPEATED_KEY, source=source, where=key)``. Syntax errors
    (:class:`json.JSONDecodeError`) and ``RecursionError`` are left to the caller, whose
    message says what its file is."""
    try:
        return json.loads(text, parse_int=parse_int, object_pairs_hook=unique_keys)
    except RepeatedKey as exc:
        raise error(REPEATED_KEY, source=source, where=exc.args[0]) from None


def _wide_encoding(data: bytes) -> str | None:
    """``"UTF-16"`` or ``"UTF-32"`` when ``data`` starts like text in one of them (a byte order
    mark, or NUL bytes among its first four, which UTF-8 text never has), else None."""
    head = data[:4]
    if head.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
        return "UTF-32"
    if head.startswith((b"\xff\xfe", b"\xfe\xff")) or (len(head) >= 2 and b"\x00" in head):
        return "UTF-32" if head.count(b"\x00") >= 3 else "UTF-16"
    return None


def decode_text(data: bytes, error, *, source: str | None, what: str, kind: str = "JSON") -> str:
    """``data`` as UTF-8 text, a leading byte order mark dropped (editors and spreadsheets on
    Windows write one).

    Raises ``error(message, source=source)`` naming the first byte that is not UTF-8 and its
    offset, e.g. ``is not UTF-8 text (byte 0xe9 at offset 61); save the scene as UTF-8 JSON``,
    or naming UTF-16 and UTF-32 text (Windows tools' "Unicode"), which without a byte order
    mark decodes as UTF-8 with NULs and would be reported as invalid at line 1 column 2.
    """
    wide = _wide_encoding(data)
    if wide:
        raise error(
            f"is {wide} text, not UTF-8; save the {what} as UTF-8 {kind}".rstrip(), source=source
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(
            f"is not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            f"save the {what} as UTF-8 {kind}".rstrip(),
            source=source,
        ) from None


def read_text(path, error, *, what: str, missing: str, kind: str = "JSON") -> str:
    """The text of the user's file ``path`` (see :func:`decode_text`).

    Parameters
    ----------
    path : str or os.PathLike
    error : type
        The located :class:`~asbuilt.errors.AsbuiltError` subclass to raise
        (``error(message, source=...)``).
    what : str
        What the file is, for messages: ``"design file"``, ``"scene"``, ``"rules file"``...
    missing : str
        The message for a file that does not exist (it names the option to check).
    kind : str
        The format the user is told to save it as (``JSON``, ``TOML``, ``CSV``).
    """
    source = os.fspath(path)
    if not source:
        raise error(f"the {what} name is empty; give the {what}", source="''")
    try:
        with open(source, "rb") as handle:
            data = handle.read()
    except FileNotFoundError:
        raise error(missing, source=source) from None
    except IsADirectoryError:
        raise error(f"is a directory; give the {what} itself", source=source) from None
    except OSError as exc:
        raise error(
            f"cannot read the {what} ({exc.strerror or exc}); check the file's permissions",
            source=source,
        ) from None
    return decode_text(data, error, source=source, what=what, kind=kind)
