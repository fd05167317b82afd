"""STEP export (AP214 by default, or AP242) with the assembly tree, names, colours, millimetres.

The solids are in metres; the writer (OpenCASCADE's XCAF STEP writer, fed by CadQuery's
``toCAF``) is told so (``xstep.cascade.unit = M``) and declares millimetres in the file
(``write.step.unit = MM``), so OpenCASCADE scales every length by 1000 on the way out. The
header names the final file and asbuilt as the originating system. :func:`read_step` reads a
file back through the XCAF document (names, tree, colours, volumes) for checks.

The file is pure 7-bit ASCII, as ISO 10303-21 (editions 2 and 3) wants of the strings a strict
reader takes: OpenCASCADE writes a name's characters beyond ASCII as raw UTF-8 bytes (and may
break a long string across lines in the middle of one), so :func:`_ascii_strings` rewrites each
such string with the standard's control directives, ``\\X2\\`` ... ``\\X0\\`` (four hex digits per
character of the Basic Multilingual Plane) and ``\\X4\\`` ... ``\\X0\\`` (eight per character beyond
it); apostrophes (``''``) and backslashes (``\\\\``) are already escaped by OpenCASCADE.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.Quantity import Quantity_Color, Quantity_ColorRGBA
from OCP.STEPCAFControl import STEPCAFControl_Reader, STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_StepModelType
from OCP.TCollection import TCollection_ExtendedString, TCollection_HAsciiString
from OCP.TDataStd import TDataStd_Name
from OCP.TDF import TDF_ChildIterator, TDF_Label, TDF_LabelSequence
from OCP.TDocStd import TDocStd_Document
from OCP.TopAbs import TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer
from OCP.XCAFDoc import (
    XCAFDoc_ColorGen,
    XCAFDoc_ColorSurf,
    XCAFDoc_ColorTool,
    XCAFDoc_DocumentTool,
)
from OCP.XSControl import XSControl_WorkSession

from asbuilt import __version__
from asbuilt.errors import ExportError

__all__ = ["SCHEMAS", "p21_escape", "write_step", "read_step", "StepSolid", "declared_length_unit"]

#: Schema names accepted by :func:`write_step` mapped to OpenCASCADE's ``write.step.schema``.
SCHEMAS = {"AP214": "AP214IS", "AP242": "AP242DIS"}


def _set(name: str, value: str) -> str:
    previous = Interface_Static.CVal_s(name)
    Interface_Static.SetCVal_s(name, value)
    return previous


#: A quoted STEP string as bytes: an apostrophe, then anything but one or a doubled one
#: (ISO 10303-21 writes an apostrophe inside a string as ``''``), then the closing apostrophe.
#: UTF-8 never uses the byte 0x27 inside a multibyte character, so this finds whole strings.
_STRING = re.compile(rb"'(?:[^']|'')*'")
#: Runs of characters beyond ASCII: those of the Basic Multilingual Plane (``\\X2\\``, UCS-2)
#: and those beyond it (``\\X4\\``, UCS-4), which need different directives.
_NON_ASCII = re.compile("([\u0080-\uffff]+)|([\U00010000-\U0010ffff]+)")


def p21_escape(text: str) -> str:
    """``text`` with every character beyond ASCII written as an ISO 10303-21 directive.

    A run of characters up to U+FFFF becomes ``\\X2\\`` followed by four upper-case hex digits
    per character and ``\\X0\\``; a run beyond U+FFFF becomes ``\\X4\\``, eight hex digits per
    character and ``\\X0\\``. ASCII characters (apostrophes and backslashes included, which the
    caller escapes) are left as they are.

    Examples
    --------
    >>> p21_escape("Rohr Ø100 泵")
    'Rohr \\\\X2\\\\00D8\\\\X0\\\\100 \\\\X2\\\\6CF5\\\\X0\\\\'
    """

    def directive(match: re.Match) -> str:
        bmp, astral = match.groups()
        if bmp:
            return "\\X2\\" + "".join(f"{ord(c):04X}" for c in bmp) + "\\X0\\"
        return "\\X4\\" + "".join(f"{ord(c):08X}" for c in astral) + "\\X0\\"

    return _NON_ASCII.sub(directive, text)


def _escape_string(match: re.Match) -> bytes:
    quoted = match.group()
    if quoted.isascii():
        return quoted
    # Line breaks inside a string are not part of it (ISO 10303-21); the writer's may split a
    # UTF-8 character, so drop them before decoding.
    text = quoted.replace(b"\r", b"").replace(b"\n", b"").decode("utf-8")
    return p21_escape(text).encode("ascii")


def _ascii_strings(path) -> None:
    """Rewrite the STEP file at ``path`` so that it is pure ASCII (see the module docstring).

    Raises
    ------
    ExportError
        When a byte beyond ASCII is outside every string, or a string is not UTF-8 (neither
        comes from OpenCASCADE's writer).
    """
    path = Path(path)
    data = path.read_bytes()
    if data.isascii():
        return
    try:
        fixed = _STRING.sub(_escape_string, data)
    except UnicodeDecodeError:
        fixed = None
    if fixed is None or not fixed.isascii():
        raise ExportError(
            "the STEP writer left text beyond ASCII that is not a UTF-8 string; "
            "report this with the model",
            source=str(path),
        )
    path.write_bytes(fixed)


def _utf8_name(text: str) -> TCollection_ExtendedString:
    """A label name holding ``text`` exactly (the multibyte flag reads the bytes as UTF-8)."""
    return TCollection_ExtendedString(text, True)


def _repair_names(doc: TDocStd_Document) -> None:
    """Fix the names CadQuery's ``toCAF`` set and name the group instances it left unnamed.

    ``toCAF`` makes each name with ``TCollection_ExtendedString(name)``, which reads the UTF-8
    bytes as Latin-1 ("Säule" becomes "SÃ¤ule" in the file); undoing that decoding is exact, as
    every character is then below U+0100. A group's instance in its parent gets no name at all
    (the writer falls back to a number in NEXT_ASSEMBLY_USAGE_OCCURRENCE), so it takes the
    name of the group it places.
    """
    main = doc.Main()
    shape_tool = XCAFDoc_DocumentTool.ShapeTool_s(main)
    for label in _labels(main):
        text = _name(label)
        if text.isascii():
            continue
        try:
            fixed = text.encode("latin-1").decode("utf-8")
        except UnicodeError:  # not a name toCAF garbled: keep it
            continue
        TDataStd_Name.Set_s(label, _utf8_name(fixed))
    for label in _labels(main):
        if shape_tool.IsComponent_s(label) and not _name(label):
            ref = TDF_Label()
            if shape_tool.GetReferredShape_s(label, ref) and _name(ref):
                TDataStd_Name.Set_s(label, _utf8_name(_name(ref)))


def _labels(root: TDF_Label):
    """Every label below ``root``; each is valid only until the next one is asked for (the
    iterator hands out its own label)."""
    iterator = TDF_ChildIterator(root, True)
    while iterator.More():
        yield iterator.Value()
        iterator.Next()


def write_step(cad, path, *, schema: str = "AP214", file_name: str | None = None) -> None:
    """Write the CAD model's assembly as STEP to ``path`` (lengths in millimetres).

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
        Solids in metres.
    path : str or Path
        Written directly; callers stage it for atomicity (:mod:`asbuilt.export`).
    schema : {"AP214", "AP242"}
    file_name : str, optional
        The name the header's FILE_NAME records (default ``path``'s name); the exporter passes
        the final name, not the temporary file's.
    """
    from cadquery.occ_impl.assembly import toCAF

    key = schema.upper()
    if key not in SCHEMAS:
        raise ExportError(
            f"unknown STEP schema {schema!r}; use one of {', '.join(SCHEMAS)}", source=str(path)
        )
    # The writer's constructor initialises the STEP statics, so create it before setting them.
    writer = STEPCAFControl_Writer(XSControl_WorkSession(), False)
    writer.SetColorMode(True)
    writer.SetLayerMode(True)
    writer.SetNameMode(True)
    previous = {
        name: _set(name, value)
        for name, value in (
            ("write.step.schema", SCHEMAS[key]),
            ("xstep.cascade.unit", "M"),  # the shapes are in metres...
            ("write.step.unit", "MM"),  # ...and the file declares millimetres
        )
    }
    try:
        _, doc = toCAF(cad.assembly(), True)  # True: colours as STEP colours
        _repair_names(doc)
        writer.Transfer(doc, STEPControl_StepModelType.STEPControl_AsIs)
        model = writer.ChangeWriter().Model()
        header = APIHeaderSection_MakeHeader(model)
        header.SetName(TCollection_HAsciiString(file_name or Path(path).name))
        header.SetOriginatingSystem(TCollection_HAsciiString(f"asbuilt {__version__}"))
        header.SetDescriptionValue(1, TCollection_HAsciiString(f"as-built model: {cad.name}"))
        header.Apply(model)
        ok = writer.Write(str(path)) == IFSelect_RetDone
    finally:
        for name, value in previous.items():
            _set(name, value)
    if not ok:
        raise ExportError("the STEP writer failed; check the disk and try again", source=str(path))
    _ascii_strings(path)


@dataclass(frozen=True)
class StepSolid:
    """One solid read back from a STEP file.

    ``name`` is its product (instance) name, ``path`` the names from the root down to it,
    ``volume`` in cubic millimetres, ``colour`` RGBA 0..1 (sRGB, as in the file) or None,
    ``solids`` the number of solids in the leaf shape, ``valid`` the kernel's validity check
    (``BRepCheck_Analyzer``) of the leaf shape as read.
    """

    name: str
    path: tuple[str, ...]
    volume: float
    colour: tuple[float, float, float, float] | None
    solids: int
    valid: bool = True


def _name(label: TDF_Label) -> str:
    if not label.IsAttribute(TDataStd_Name.GetID_s()):
        return ""  # (FindAttribute on a label without one crashes through OCP)
    attr = TDataStd_Name()
    if label.FindAttribute(TDataStd_Name.GetID_s(), attr):
        return str(attr.Get().ToExtString())
    return ""


def _colour(color_tool, label: TDF_Label, shape) -> tuple[float, float, float, float] | None:
    colour = Quantity_ColorRGBA()
    found = any(
        XCAFDoc_ColorTool.GetColor_s(label, kind, colour)
        for kind in (XCAFDoc_ColorSurf, XCAFDoc_ColorGen)
    ) or color_tool.GetColor(shape, XCAFDoc_ColorSurf, colour)
    if not found:
        return None
    rgb = colour.GetRGB()
    srgb = (
        Quantity_Color.Convert_LinearRGB_To_sRGB_s(c) for c in (rgb.Red(), rgb.Green(), rgb.Blue())
    )
    return (*srgb, colour.Alpha())


def _count_solids(shape) -> int:
    explorer = TopExp_Explorer(shape, TopAbs_SOLID)
    count = 0
    while explorer.More():
        count += 1
        explorer.Next()
    return count


def read_step(path) -> list[StepSolid]:
    """Read a STEP file's leaf solids with their names, tree paths, volumes and colours.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    list of StepSolid
        In the file's tree order; volumes in mm^3 whatever unit the file declares.
    """
    previous_unit = _set("xstep.cascade.unit", "MM")
    try:
        reader = STEPCAFControl_Reader()
        reader.SetColorMode(True)
        reader.SetNameMode(True)
        if reader.ReadFile(str(path)) != IFSelect_RetDone:
            raise ExportError("not a readable STEP file", source=str(path))
        doc = TDocStd_Document(TCollection_ExtendedString("XmlXCAF"))
        reader.Transfer(doc)
    finally:
        _set("xstep.cascade.unit", previous_unit)
    shape_tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    color_tool = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    found: list[StepSolid] = []

    def leaf(label: TDF_Label, instance: TDF_Label, trail: tuple[str, ...]) -> None:
        shape = shape_tool.GetShape_s(label)
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(shape, props)
        colour = _colour(color_tool, instance, shape) or _colour(color_tool, label, shape)
        valid = BRepCheck_Analyzer(shape).IsValid()
        found.append(StepSolid(trail[-1], trail, props.Mass(), colour, _count_solids(shape), valid))

    def visit(label: TDF_Label, trail: tuple[str, ...]) -> None:
        components = TDF_LabelSequence()
        shape_tool.GetComponents_s(label, components)
        for i in range(1, components.Length() + 1):
            comp = components.Value(i)
            ref = TDF_Label()
            shape_tool.GetReferredShape_s(comp, ref)
            name = _name(comp) or _name(ref)
            if shape_tool.IsAssembly_s(ref):
                visit(ref, (*trail, _name(ref) or name))
            else:
                leaf(ref, comp, (*trail, name))

    roots = TDF_LabelSequence()
    shape_tool.GetFreeShapes(roots)
    for i in range(1, roots.Length() + 1):
        root = roots.Value(i)
        if shape_tool.IsAssembly_s(root):
            visit(root, (_name(root),))
        else:
            leaf(root, root, (_name(root),))
    return found


_UNIT = re.compile(r"LENGTH_UNIT\(\)\s*NAMED_UNIT\(\*\)\s*SI_UNIT\((\.\w+\.|\$),\s*\.METRE\.\)")


def declared_length_unit(path) -> str:
    """The length unit a STEP file declares: ``"mm"``, ``"m"``, ``"cm"``..., read from its text.

    Raises
    ------
    ExportError
        When the file declares no SI length unit.
    """
    text = Path(path).read_text(encoding="latin-1")
    match = _UNIT.search(text)
    if match is None:
        raise ExportError("the STEP file declares no SI length unit", source=str(path))
    prefix = {"$": "", ".MILLI.": "m", ".CENTI.": "c", ".KILO.": "k", ".DECI.": "d"}
    return prefix.get(match.group(1), match.group(1).strip(".").lower()) + "m"
