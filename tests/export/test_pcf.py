"""PCF: the piping as ISOGEN component records, read back by a parser written from the format's
layout (unindented identifiers, indented attribute records)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from asbuilt.cli import main
from asbuilt.errors import ExportError
from asbuilt.export import export_model
from asbuilt.export.pcf import pcf_text, write_pcf
from asbuilt.model import Bend, Component, Model, Reducer, Spool, Straight
from asbuilt.pipeline import build_model
from asbuilt.scan import load_scan

R4, W4 = 0.1143 / 2, 0.00602  # NPS 4 STD (ASME B36.10M)
R6, W6 = 0.1683 / 2, 0.00711  # NPS 6 STD


def parse(text: str) -> tuple[dict, list[dict]]:
    """(header records, blocks): each block is ``{"type", "pipeline", records...}`` where a
    record name maps to the list of its value lists (floats where they parse)."""
    header: dict = {}
    blocks: list[dict] = []
    pipeline = None
    current = None
    for line in text.splitlines():
        if not line.strip():
            continue
        indented = line.startswith(" ")
        name, *values = line.split()
        if not indented:
            if name.startswith("UNITS-") or name == "ISOGEN-FILES":
                header[name] = values
                current = None
                continue
            if name == "PIPELINE-REFERENCE":
                pipeline = " ".join(values)
                current = {"type": name, "pipeline": pipeline}
            else:
                current = {"type": name, "pipeline": pipeline, "values": values}
            blocks.append(current)
            continue
        parsed = []
        for value in values:
            try:
                parsed.append(float(value))
            except ValueError:
                parsed.append(value)
        current.setdefault(name, []).append(parsed)
    return header, blocks


def _components(blocks):
    return [b for b in blocks if b["type"] not in ("PIPELINE-REFERENCE", "MATERIALS", "ITEM-CODE")]


def _by_id(blocks):
    return {b["COMPONENT-ATTRIBUTE1"][0][0]: b for b in _components(blocks)}


def _point(record) -> np.ndarray:
    return np.array(record[:3], dtype=float) / 1000.0


def test_zoo_piping_is_written_once_each_and_nothing_else(zoo, tmp_path):
    path = tmp_path / "zoo.pcf"
    write_pcf(zoo, path)
    raw = path.read_bytes()
    assert raw.isascii() and b"\r\n" in raw
    header, blocks = parse(raw.decode("ascii"))
    assert header["UNITS-CO-ORDS"] == ["MM"] and header["UNITS-BORE"] == ["INCH"]
    found = _by_id(blocks)
    assert set(found) == {"P1", "E1", "P2", "T1", "R1"}  # no cylinder, cuboid, sphere...
    assert [found[i]["type"] for i in ("P1", "E1", "T1", "R1")] == [
        "PIPE",
        "ELBOW",
        "TEE",
        "REDUCER-CONCENTRIC",
    ]
    # Spool S1 is one pipeline; the tee and reducer, in no spool, one each.
    assert {found[i]["pipeline"] for i in ("P1", "E1", "P2")} == {"S1"}
    # Every item code is described under MATERIALS.
    codes = {b["ITEM-CODE"][0][0] for b in _components(blocks)}
    described = {b["values"][0] for b in blocks if b["type"] == "ITEM-CODE"}
    assert codes == described


def test_end_points_and_bores_match_the_model_and_the_catalog(zoo):
    _, blocks = parse(pcf_text(zoo))
    found = _by_id(blocks)
    p1 = zoo.component("P1").geometry
    ends = found["P1"]["END-POINT"]
    assert _point(ends[0]) == pytest.approx(p1.start, abs=5e-5)
    assert _point(ends[1]) == pytest.approx(p1.end, abs=5e-5)
    assert [e[3] for e in ends] == [4.0, 4.0]  # NPS 4
    reducer = found["R1"]["END-POINT"]
    assert [e[3] for e in reducer] == [4.0, 3.0]  # 114.3 -> 88.9 mm OD: NPS 4 x 3
    tee = found["T1"]
    assert tee["BRANCH1-POINT"][0][3] == 3.0
    assert _point(tee["CENTRE-POINT"][0]) == pytest.approx([3, 0, 0], abs=5e-5)
    assert found["T1"]["SKEY"] == [["TEBW"]] and found["R1"]["SKEY"] == [["RCBW"]]


def test_elbow_centre_point_is_where_the_end_tangents_meet(zoo):
    """A 90 degree elbow's tangent point lies one centre-to-end dimension (here the bend
    radius, 0.2 m) from each end, along each end's direction."""
    _, blocks = parse(pcf_text(zoo))
    elbow = _by_id(blocks)["E1"]
    corner = _point(elbow["CENTRE-POINT"][0])
    assert corner == pytest.approx([1.2, 0.0, 0.0], abs=5e-5)
    assert elbow["ANGLE"] == [[9000.0]]


def test_spool_sample_elbow_and_tee_dimensions_are_b16_9(tmp_path):
    """Centre-to-end of the sample's NPS 6 long-radius elbow (229 mm), NPS 4 elbow (152 mm) and
    NPS 6 tee run (143 mm): ASME B16.9 tables (standards.md), within the 2 mm tolerance."""
    model = build_model(load_scan("samples/spool.json"))
    _, blocks = parse(pcf_text(model))
    spans = {}
    for block in _components(blocks):
        if block["type"] in ("ELBOW", "TEE"):
            corner = np.array(block["CENTRE-POINT"][0])
            bore = block["END-POINT"][0][3]
            spans.setdefault((block["type"], bore), []).extend(
                float(np.linalg.norm(np.array(e[:3]) - corner)) for e in block["END-POINT"]
            )
    assert spans[("ELBOW", 6.0)] == pytest.approx([229.0] * len(spans[("ELBOW", 6.0)]), abs=2)
    assert spans[("ELBOW", 4.0)] == pytest.approx([152.0] * len(spans[("ELBOW", 4.0)]), abs=2)
    assert spans[("TEE", 6.0)] == pytest.approx([143.0] * len(spans[("TEE", 6.0)]), abs=2)


@pytest.mark.parametrize(
    ("flat", "expected"), [((0, 0, 1), "UP"), ((0, 0, -1), "DOWN"), ((0, -1, 0), "SOUTH")]
)
def test_eccentric_reducer_names_its_flat_side(flat, expected):
    flat = np.array(flat, dtype=float)
    step = R6 - R4
    # From the large end: the small end's axis moves towards the flat side by the radii's step.
    reducer = Reducer([0, 0, 0], np.array([0.14, 0, 0]) + step * flat, R6, R4, offset=step * flat)
    model = Model(
        components=(Component("R1", "reducer", reducer, nominal="6", schedule="STD"),),
        catalog="asme-b36.10m",
    )
    _, blocks = parse(pcf_text(model))
    block = _by_id(blocks)["R1"]
    assert block["type"] == "REDUCER-ECCENTRIC"
    assert block["SKEY"] == [["REBW"]]
    assert block["FLAT-DIRECTION"] == [[expected]]
    assert [e[3] for e in block["END-POINT"]] == [6.0, 4.0]


def test_dn_catalog_writes_millimetre_bores():
    """EN 10220 DN 100 has OD 114.3 mm; its bore is written as 100 with UNITS-BORE MM."""
    pipe = Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], 0.1143 / 2), nominal="100")
    model = Model(components=(pipe,), catalog="en-10220")
    header, blocks = parse(pcf_text(model))
    assert header["UNITS-BORE"] == ["MM"]
    assert [e[3] for e in _by_id(blocks)["P1"]["END-POINT"]] == [100.0, 100.0]


def test_unsnapped_pipe_writes_its_outside_diameter_as_bore():
    pipe = Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], 0.05))  # 100 mm: no NPS
    model = Model(components=(pipe,), catalog="asme-b36.10m")
    _, blocks = parse(pcf_text(model))
    assert _by_id(blocks)["P1"]["END-POINT"][0][3] == pytest.approx(100 / 25.4, abs=1e-3)


def test_names_are_written_as_ascii():
    pipe = Component("Säule-1", "pipe", Straight([0, 0, 0], [1, 0, 0], R4, W4), nominal="4")
    model = Model(
        components=(pipe,),
        catalog="asme-b36.10m",
        name="储罐 line\nnext",
        spools=(Spool("S1", ("Säule-1",)),),
    )
    text = pcf_text(model)
    assert text.isascii()
    assert "PROJECT-IDENTIFIER ?? line next" in text
    assert re.search(r"COMPONENT-ATTRIBUTE1 Saule-1~[0-9a-f]{8}\r\n", text)


def _two_lines() -> Model:
    """Two spools whose names (and components' ids) differ only by letters beyond ASCII."""
    components, spools = [], []
    for k, (line, ids) in enumerate(
        (("LINE-Ä", ("P-Ä1", "P-Ö1")), ("LINE-Ö", ("P-Ü1", "P-泵"))), start=1
    ):
        for j, ident in enumerate(ids):
            y = float(k + j)
            pipe = Straight([0, y, 0], [1, y, 0], R4, W4)
            components.append(Component(ident, "pipe", pipe, nominal="4", group=line))
        spools.append(Spool(line, ids))
    plain = Component("P-A1", "pipe", Straight([0, 9, 0], [1, 9, 0], R4, W4), nominal="4")
    components.append(plain)  # a plain ASCII id next to the transliterated ones keeps its name
    return Model(components=tuple(components), catalog="asme-b36.10m", spools=tuple(spools))


def test_distinct_names_stay_distinct_in_ascii():
    """``LINE-Ä`` and ``LINE-Ö`` were both written ``LINE-?``: one pipeline for two spools."""
    text = pcf_text(_two_lines())
    assert text.isascii()
    _, blocks = parse(text)
    references = [b["pipeline"] for b in blocks if b["type"] == "PIPELINE-REFERENCE"]
    assert len(references) == len(set(references)) == 3
    assert [r.split("~")[0] for r in references] == ["LINE-A", "LINE-O", "P-A1"]
    ids = [b["COMPONENT-ATTRIBUTE1"][0][0] for b in _components(blocks)]
    assert len(set(ids)) == 5
    assert [i.split("~")[0] for i in ids] == ["P-A1", "P-O1", "P-U1", "P-?", "P-A1"]
    assert ids[-1] == "P-A1"
    by_pipeline = {b["pipeline"]: b["ATTRIBUTE1"][0][0] for b in blocks if "ATTRIBUTE1" in b}
    assert all(group == ref for ref, group in by_pipeline.items())


def test_ascii_names_are_the_same_from_file_to_file():
    """The digest depends on the name alone: the same spool gets the same reference in a file
    of its own as next to other spools."""
    model = _two_lines()
    alone = Model(
        components=tuple(c for c in model.components if c.group == "LINE-Ö"),
        catalog="asme-b36.10m",
        spools=(model.spools[1],),
    )
    assert "LINE-Ö" in alone.spools[0].id and len(alone.components) == 2

    def reference(text):
        return [line for line in text.splitlines() if line.startswith("PIPELINE-REFERENCE")]

    assert reference(pcf_text(alone))[0] == reference(pcf_text(model))[1]


def test_a_model_without_piping_is_refused(tmp_path):
    column = Component("C1", "cylinder", Straight([0, 0, 0], [0, 0, 3], 0.15))
    model = Model(components=(column,))
    target = tmp_path / "x.pcf"
    with pytest.raises(ExportError, match="no piping"):
        export_model(model, target)
    assert not target.exists()


def test_cli_writes_pcf_and_refuses_a_scan_without_piping(tmp_path, capsys):
    target = tmp_path / "spool.pcf"
    assert main(["model", "samples/spool.json", "--out", str(target), "--quiet"]) == 0
    _, blocks = parse(target.read_text(encoding="ascii"))
    assert {b["type"] for b in _components(blocks)} >= {"PIPE", "ELBOW", "TEE"}
    scan = tmp_path / "wall.json"
    scan.write_text(
        '{"format": "asbuilt-scan", "version": 1, "units": "m", "objects": [{"id": "W1", '
        '"kind": "plane", "points": [[0, 5, 0], [1, 5, 0], [0, 5, 1], [1, 5, 1], [0.5, 5, 0.5]]}]}'
    )
    capsys.readouterr()
    assert main(["model", str(scan), "--out", str(tmp_path / "wall.pcf"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no piping" in err[0] and "wall.pcf" in err[0]
    assert not (tmp_path / "wall.pcf").exists()


def test_a_user_catalog_file_gives_the_bores(tmp_path):
    """A user catalog whose name is a shipped one's: its own sizes give the bores (here a
    110 mm OD pipe, size "110", in a DN catalog), read from the file the model records."""
    path = tmp_path / "mine.csv"
    path.write_text(
        "# name: asme-b36.10m\n# title: PE pipe\n# standard: none\n# kind: pipe\n"
        "# units: mm\n# designation: DN\nnominal,dn,od,source\n110,100,110.0,table A\n"
    )
    pipe = Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], 0.055), nominal="110")
    model = Model(components=(pipe,), catalog="asme-b36.10m", catalog_file=str(path))
    header, blocks = parse(pcf_text(model))
    assert header["UNITS-BORE"] == ["MM"]
    assert _by_id(blocks)["P1"]["END-POINT"][0][3] == 100.0


@pytest.mark.parametrize(("standard", "code"), [(True, "ELBOW-6IN-STD"), (False, None)])
def test_a_non_standard_elbow_gets_its_own_item_code(standard, code):
    """A 60 degree elbow cut from a 90 was written as ELBOW-6IN-STD, the 90 degree elbow's
    item code: a take-off from the isometric counted it as a catalog elbow."""
    # R 229 mm about (0, 0.229, 0) from the origin, turning 60 degrees
    end = [0.229 * np.sin(np.radians(60)), 0.229 * (1 - np.cos(np.radians(60))), 0]
    bend = Bend([0, 0, 0], end, [0, 0.229, 0], R6, W6)
    snap = {"status": "fitting", "angle_deg": 60.0, "standard": standard}
    snap["dimensions"] = "asme-b16.9" + ("" if standard else ", cut from a 90 degree elbow")
    elbow = Component("E1", "elbow", bend, nominal="6", schedule="STD", snap=snap)
    _, blocks = parse(pcf_text(Model(components=(elbow,), catalog="asme-b36.10m")))
    (written,) = _by_id(blocks)["E1"]["ITEM-CODE"]
    described = {b["values"][0]: b for b in blocks if b["type"] == "ITEM-CODE"}
    if standard:
        assert written == [code]
        return
    assert written == ["ELBOW-6IN-STD-60DEG-NONSTD"]
    assert "cut from a" in " ".join(
        " ".join(map(str, v)) for v in described[written[0]]["DESCRIPTION"]
    )


def test_a_reducing_elbow_writes_each_ends_bore(elbow_6x4):
    """An elbow between NPS 6 and NPS 4 pipes: END-POINT bores 6 and 4, each the bore of the
    pipe welded there (it wrote 6 at both ends), and a two-size item code."""
    _, blocks = parse(pcf_text(elbow_6x4))
    found = _by_id(blocks)
    ends = found["P1-P2"]["END-POINT"]
    assert [e[3] for e in ends] == [6.0, 4.0]
    for pipe_id in ("P1", "P2"):
        for pipe_end in found[pipe_id]["END-POINT"]:
            for end in ends:
                if np.allclose(_point(end), _point(pipe_end), atol=5e-5):
                    assert end[3] == pipe_end[3], pipe_id
    assert found["P1-P2"]["ITEM-CODE"] == [["ELBOW-6X4IN-40"]]
