"""Catalog data against independent tables, the loader's errors and nominal-size hints.

Truth values are copied by hand from the project's standards reference
(/work/shared/reference/standards.md: B36.10M/B36.19M tables via CalebBell/fluids cross-checked
with manufacturer tables; B16.9 from public fitting tables), not read from the catalog files.
"""

from __future__ import annotations

import math

import pytest

from asbuilt.catalog import (
    DEFAULT_CATALOG,
    catalog_names,
    fitting_dims,
    load_catalog,
    parse_catalog,
    parse_nominal,
)
from asbuilt.errors import CatalogError

INCH = 25.4


def test_shipped_catalogs_are_listed():
    assert set(catalog_names()) >= {
        "asme-b36.10m",
        "asme-b36.19m",
        "en-10220",
        "astm-b88",
        "astm-d1785",
        "asme-b16.9",
    }
    assert DEFAULT_CATALOG == "asme-b36.10m"


@pytest.mark.parametrize(
    "name", ["asme-b36.10m", "asme-b36.19m", "en-10220", "astm-b88", "astm-d1785", "asme-b16.9"]
)
def test_every_row_has_a_source_and_header(name):
    cat = load_catalog(name)
    assert cat.name == name and cat.standard and cat.title
    rows = cat.sizes if cat.kind == "pipe" else cat.fittings
    assert len(rows) > 10
    assert all(row.source for row in rows)
    if cat.kind == "pipe":
        ods = [s.od for s in cat.sizes]
        assert ods == sorted(ods) and len(set(ods)) == len(ods)


# (NPS, DN, OD mm, STD, 40, XS, 80) from the standards reference table
B36_10M = [
    ("1/8", 6, 10.3, 1.73, 1.73, 2.41, 2.41),
    ("1/2", 15, 21.3, 2.77, 2.77, 3.73, 3.73),
    ("1", 25, 33.4, 3.38, 3.38, 4.55, 4.55),
    ("2", 50, 60.3, 3.91, 3.91, 5.54, 5.54),
    ("3", 80, 88.9, 5.49, 5.49, 7.62, 7.62),
    ("4", 100, 114.3, 6.02, 6.02, 8.56, 8.56),
    ("6", 150, 168.3, 7.11, 7.11, 10.97, 10.97),
    ("10", 250, 273.0, 9.27, 9.27, 12.70, 15.09),
    ("12", 300, 323.8, 9.53, 10.31, 12.70, 17.48),
    ("16", 400, 406.4, 9.53, 12.70, 12.70, 21.44),
    ("24", 600, 610.0, 9.53, 17.48, 12.70, 30.96),
]


@pytest.mark.parametrize(("nps", "dn", "od", "std", "s40", "xs", "s80"), B36_10M)
def test_b36_10m_spot_checks(nps, dn, od, std, s40, xs, s80):
    cat = load_catalog("asme-b36.10m")
    size = cat.size(nps)
    assert size.dn == dn
    assert size.od == pytest.approx(od / 1000)
    for schedule, wall in (("STD", std), ("40", s40), ("XS", xs), ("80", s80)):
        assert size.wall(schedule) == pytest.approx(wall / 1000), schedule


def test_b36_10m_reaches_nps_48_with_od_equal_to_nps_from_14_up():
    cat = load_catalog("asme-b36.10m")
    assert cat.size("48").od == pytest.approx(1.219)
    for size in cat.sizes:
        if size.nps >= 14:
            assert size.od == pytest.approx(size.nps * INCH / 1000, abs=0.6e-3)


def test_b36_10m_smallest_od_gap_from_half_inch_up_is_5_4_mm():
    sizes = [s for s in load_catalog("asme-b36.10m").sizes if s.nps >= 0.5]
    gaps = [b.od - a.od for a, b in zip(sizes, sizes[1:])]
    assert min(gaps) == pytest.approx(0.0054)


@pytest.mark.parametrize(
    ("nps", "od", "s5", "s10"),
    [
        ("1/2", 21.3, 1.65, 2.11),
        ("4", 114.3, 2.11, 3.05),
        ("10", 273.1, 3.40, 4.19),
        ("12", 323.9, 3.96, 4.57),
        ("24", 610.0, 5.54, 6.35),
    ],
)
def test_b36_19m_spot_checks(nps, od, s5, s10):
    size = load_catalog("asme-b36.19m").size(nps)
    assert size.od == pytest.approx(od / 1000)
    assert size.wall("5s") == pytest.approx(s5 / 1000)
    assert size.wall("10S") == pytest.approx(s10 / 1000)


@pytest.mark.parametrize(
    ("dn", "od"), [(20, 26.9), (25, 33.7), (65, 76.1), (100, 114.3), (125, 139.7), (300, 323.9)]
)
def test_en_10220_metric_ods(dn, od):
    cat = load_catalog("en-10220")
    assert cat.size(str(dn)).od == pytest.approx(od / 1000)
    assert cat.size(f"DN{dn}").od == pytest.approx(od / 1000)


def test_b88_od_is_nominal_plus_an_eighth():
    for size in load_catalog("astm-b88").sizes:
        assert size.od == pytest.approx((size.nps + 0.125) * INCH / 1000)


@pytest.mark.parametrize(
    ("nominal", "k", "l", "m"),
    [
        ("1/2", 0.049, 0.040, 0.028),
        ("3/4", 0.065, 0.045, 0.032),
        ("1", 0.065, 0.050, 0.035),
        ("2", 0.083, 0.070, 0.058),
        ("4", 0.134, 0.110, 0.095),
        ("6", 0.192, 0.140, 0.122),
    ],
)
def test_b88_walls(nominal, k, l, m):  # noqa: E741
    size = load_catalog("astm-b88").size(nominal)
    for schedule, wall in (("K", k), ("L", l), ("M", m)):
        assert size.wall(schedule) == pytest.approx(wall * INCH / 1000)


def test_pvc_has_steel_ods_and_steel_schedule_40_walls():
    steel = load_catalog("asme-b36.10m")
    for size in load_catalog("astm-d1785").sizes:
        other = steel.size(size.nominal)
        assert size.od == pytest.approx(other.od, abs=0.5e-3)  # IPS 24.000 in = 609.6 mm
        assert size.wall("40") == pytest.approx(other.wall("40"), abs=0.05e-3)


# (NPS, 90 LR, 90 SR, 45 LR, tee, reducer) from the standards reference, mm
B16_9 = [
    ("1", 38, 25, 22, 38, 51),
    ("1 1/2", 57, 38, 29, 57, 64),
    ("2", 76, 51, 35, 64, 76),
    ("3", 114, 76, 51, 86, 89),
    ("4", 152, 102, 64, 105, 102),
    ("6", 229, 152, 95, 143, 140),
    ("8", 305, 203, 127, 178, 152),
    ("10", 381, 254, 159, 216, 178),
    ("12", 457, 305, 190, 254, 203),
    ("16", 610, 406, 254, 305, 356),
    ("24", 914, 610, 381, 432, 508),
]


@pytest.mark.parametrize(("nps", "lr", "sr", "l45", "tee", "red"), B16_9)
def test_b16_9_spot_checks(nps, lr, sr, l45, tee, red):
    pipe = load_catalog("asme-b36.10m")
    row = pipe.fitting(pipe.size(nps))
    assert row is not None
    assert row.dims["elbow90_lr"] == pytest.approx(lr / 1000)
    assert row.dims["elbow90_sr"] == pytest.approx(sr / 1000)
    assert row.dims["elbow45_lr"] == pytest.approx(l45 / 1000)
    assert row.dims["tee_run"] == pytest.approx(tee / 1000)
    assert row.dims["reducer"] == pytest.approx(red / 1000)


# Straight tees, centre-to-end C (run) and M (outlet), mm, every row NPS 1/2 to 24, hand-copied
# from wermac.org's "Dimensions butt welded Straight Tees ASME B16.9 NPS 1/2 - 48" (mirrored at
# https://alloysteelfittings.com/dim_tees_eq.html); C = M for all of them.
B16_9_TEES = {
    "1/2": 25,
    "3/4": 29,
    "1": 38,
    "1 1/4": 48,
    "1 1/2": 57,
    "2": 64,
    "2 1/2": 76,
    "3": 86,
    "3 1/2": 95,
    "4": 105,
    "5": 124,
    "6": 143,
    "8": 178,
    "10": 216,
    "12": 254,
    "14": 279,
    "16": 305,
    "18": 343,
    "20": 381,
    "22": 419,
    "24": 432,
}


def test_b16_9_straight_tees_every_row():
    table = load_catalog("asme-b16.9")
    rows = {row.nominal: row for row in table.fittings}
    assert set(rows) == set(B16_9_TEES)
    for nps, c in B16_9_TEES.items():
        assert rows[nps].dims["tee_run"] == pytest.approx(c / 1000), nps
        assert rows[nps].dims["tee_outlet"] == pytest.approx(c / 1000), nps
        assert "dim_tees_eq" in rows[nps].source, nps


def test_b16_9_rows_follow_the_elbow_rules():
    """LR = 1.5 x NPS and SR = 1.0 x NPS (NPS 1 up); the 45 degree centre-to-end B is within
    5 mm of R tan(22.5 deg) or longer (small 45 degree elbows have longer ends), and within 3 mm
    (B is rounded to 1/8 in) for NPS 4 to 20."""
    for row in load_catalog("asme-b16.9").fittings:
        lr = row.dims["elbow90_lr"]
        tangent = lr * math.tan(math.radians(22.5))
        assert row.dims["elbow45_lr"] >= tangent - 5e-3
        if 4 <= row.nps <= 20:
            assert row.dims["elbow45_lr"] == pytest.approx(tangent, abs=3e-3)
        if row.nps >= 1:
            assert lr == pytest.approx(1.5 * row.nps * INCH / 1000, abs=1e-3)
            assert row.dims["elbow90_sr"] == pytest.approx(row.nps * INCH / 1000, abs=1e-3)


def test_fitting_dims_from_table_and_by_rule():
    steel = load_catalog("asme-b36.10m")
    four = steel.size("4")
    dims = fitting_dims(steel, four, four.od)
    assert (dims.bend_radius, dims.tee_run, dims.reducer_length, dims.source) == (
        pytest.approx(0.152),
        pytest.approx(0.105),
        pytest.approx(0.102),
        "asme-b16.9",
    )
    assert fitting_dims(steel, four, four.od, "short").bend_radius == pytest.approx(0.102)
    half = steel.size("1/2")
    short = fitting_dims(steel, half, half.od, "short")
    assert short.bend_radius == pytest.approx(0.038) and "long radius used" in short.notes[0]
    copper = load_catalog("astm-b88")
    two = copper.size("2")
    ruled = fitting_dims(copper, two, two.od)
    assert ruled.source == "rule"
    assert ruled.bend_radius == pytest.approx(1.5 * 2 * INCH / 1000)
    assert ruled.tee_run == pytest.approx(two.od)
    assert "bend radius by rule 1.5 x nominal bore" in ruled.notes
    # A pipe of no catalog size (an ambiguous snap): the rule's bore is its OD, and says so.
    unsized = fitting_dims(steel, None, 0.187)
    assert unsized.bend_radius == pytest.approx(1.5 * 0.187)
    assert "bend radius by rule 1.5 x OD (no nominal size)" in unsized.notes
    with pytest.raises(ValueError):
        fitting_dims(steel, four, four.od, "medium")


@pytest.mark.parametrize(
    ("text", "system", "value", "steel", "metric"),
    [
        ('4"', "nps", 4.0, "4", "100"),
        ("4 in", "nps", 4.0, "4", "100"),
        ("4in", "nps", 4.0, "4", "100"),
        ("NPS 4", "nps", 4.0, "4", "100"),
        ("nps 1 1/2", "nps", 1.5, "1 1/2", "40"),
        ('1-1/2"', "nps", 1.5, "1 1/2", "40"),
        ("DN100", "dn", 100.0, "4", "100"),
        ("DN 150", "dn", 150.0, "6", "150"),
        ("100", "number", 100.0, "4", "100"),
        ("4", "number", 4.0, "4", "100"),
        ("3/4", "number", 0.75, "3/4", "20"),
        # Forms operators write (audit): JIS A (mm) and B (inch) sizes, "in." and "-inch",
        # and a schedule, weight class or rating after the size.
        ("100A", "dn", 100.0, "4", "100"),
        ("4B", "nps", 4.0, "4", "100"),
        ("4 in.", "nps", 4.0, "4", "100"),
        ("4-inch", "nps", 4.0, "4", "100"),
        ('4" sch 40', "nps", 4.0, "4", "100"),
        ('4" STD', "nps", 4.0, "4", "100"),
        ('1 1/2" XS', "nps", 1.5, "1 1/2", "40"),
        ("4 in, Schedule 80", "nps", 4.0, "4", "100"),
        ('6" 150#', "nps", 6.0, "6", "150"),
        ("DN100 PN16", "dn", 100.0, "4", "100"),
        # "NPS" and an inch unit together (the unit said twice), as line lists write them
        ('NPS 4"', "nps", 4.0, "4", "100"),
        ('NPS 1-1/2"', "nps", 1.5, "1 1/2", "40"),
        ("NPS 4 in", "nps", 4.0, "4", "100"),
        ('nps6"', "nps", 6.0, "6", "150"),
        # a hyphen after DN or NPS, as in tag numbers ("DN-100", "NPS-4")
        ("DN-100", "dn", 100.0, "4", "100"),
        ("NPS-4", "nps", 4.0, "4", "100"),
    ],
)
def test_nominal_hints(text, system, value, steel, metric):
    hint = parse_nominal(text)
    assert (hint.system, hint.value) == (system, value)
    assert load_catalog("asme-b36.10m").match_hint(hint).nominal == steel
    assert load_catalog("en-10220").match_hint(hint).nominal == metric


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("4\u2033", 4.0),  # double prime
        ("4\u201c", 4.0),  # left double quotation mark (autocorrect)
        ("4\u201d", 4.0),  # right double quotation mark
        ("4\u2032\u2032", 4.0),  # two primes
        ('1\u20442"', 0.5),  # fraction slash
        ('1 1\u20442"', 1.5),
        ('\u215d"', 0.625),  # vulgar fraction five eighths
        ('\u215e"', 0.875),
    ],
)
def test_nominal_hints_typed_with_typographic_marks(text, value):
    hint = parse_nominal(text)
    assert (hint.system, hint.value) == ("nps", value)


def test_five_eighths_copper_hint_names_the_five_eighths_tube():
    """ASTM B88 has a 5/8 tube, OD = nominal + 1/8 in = 0.750 in (standards reference)."""
    tube = load_catalog("astm-b88").match_hint(parse_nominal('\u215d"'))
    assert tube.nominal == "5/8" and tube.od == pytest.approx(0.750 * INCH / 1000)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "abc",
        "DN",
        "NPS",
        "-4",
        "4/0",
        None,
        "sch 40",
        "PN16",
        "3000 ID",
        "100 mm",
        # no size is zero: a DN or JIS A hint of 0 is as unreadable as "4/0" or "NPS 0"
        "DN 0",
        "DN0.0",
        "0A",
        "NPS 0",
        '0"',
    ],
)
def test_nominal_hints_not_understood(text):
    assert parse_nominal(text) is None


def test_bare_number_reads_the_catalogs_own_designation_first():
    # "6" is NPS 6 for an NPS catalog and DN 6 for a DN catalog
    hint = parse_nominal("6")
    assert load_catalog("asme-b36.10m").match_hint(hint).od == pytest.approx(0.1683)
    assert load_catalog("en-10220").match_hint(hint).od == pytest.approx(0.0102)


def test_bare_number_falls_back_to_the_other_designation_only_when_the_catalog_lacks_it():
    """docs/catalogs.md: "40" is NPS 40 (OD 40 in = 1016 mm, B36.10M) where the catalog has NPS 40,
    else DN 40 (NPS 1 1/2, 48.3 mm); "25" is DN 25 (NPS 1, 33.4 mm) in an NPS catalog."""
    forty, twenty_five = parse_nominal("40"), parse_nominal("25")
    steel = load_catalog("asme-b36.10m")
    assert steel.match_hint(forty).od == pytest.approx(1.016)
    assert steel.match_hint(twenty_five).od == pytest.approx(0.0334)
    assert load_catalog("asme-b36.19m").match_hint(forty).od == pytest.approx(0.0483)
    assert steel.match_hint(parse_nominal("DN40")).od == pytest.approx(0.0483)


GOOD = """# name: mine
# title: Test pipe
# standard: none
# kind: pipe
# units: mm
nominal,od,wall_std,source
2,60.3,3.91,table A
4,114.3,6.02,table A
"""


def test_user_catalog_saved_with_a_byte_order_mark(tmp_path):
    """Spreadsheets save "CSV UTF-8" with a BOM before the first header line."""
    path = tmp_path / "bom.csv"
    path.write_bytes(GOOD.encode("utf-8-sig"))
    assert load_catalog(path).name == "mine"


def test_user_catalog_by_path(tmp_path):
    path = tmp_path / "mine.csv"
    path.write_text(GOOD)
    cat = load_catalog(str(path))
    assert cat.name == "mine" and [s.nominal for s in cat.sizes] == ["2", "4"]
    assert cat.wall("4", "std") == pytest.approx(0.00602)
    assert load_catalog(path).sizes[0].od == pytest.approx(0.0603)


def test_user_catalog_with_fittings_beside_it(tmp_path):
    (tmp_path / "fit.csv").write_text(
        "# name: fit\n# kind: fittings\n# units: in\n"
        "nominal,elbow90_lr,tee_run,source\n4,6,4.12,my table\n"
    )
    (tmp_path / "mine.csv").write_text(
        GOOD.replace("# units: mm", "# units: mm\n# fittings: fit.csv")
    )
    cat = load_catalog(tmp_path / "mine.csv")
    dims = fitting_dims(cat, cat.size("4"), 0.1143)
    assert dims.bend_radius == pytest.approx(0.1524) and dims.source == "fit"


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        (GOOD.replace("114.3", "abc"), "line 8, column 'od'", "not a number"),
        (GOOD.replace("6.02", "-1"), "line 8, column 'wall_std'", "positive"),
        (GOOD.replace("6.02", "60"), "line 8, column 'wall_std'", "thinner"),
        (GOOD.replace(",table A\n4", ",\n4"), "line 7, column 'source'", "source"),
        (GOOD.replace("2,60.3", "4,60.3"), "line 8, column 'nominal'", "repeats line 7"),
        (GOOD.replace("4,114.3,6.02,table A", "4,114.3,table A"), "line 8", "3 cells but 4"),
        (GOOD.replace("wall_std", "colour"), "line 6, column 'colour'", "unknown column"),
        (GOOD.replace("nominal,od", "nominal,odd"), "line 6", "missing column 'od'"),
        (GOOD.replace("# kind: pipe", "# kind: valve"), "header 'kind'", "pipe or fittings"),
        (GOOD.replace("# units: mm", "# units: furlong"), "header 'units'", "units must be"),
        (GOOD.replace("# name: mine\n", ""), "header", "name"),
        (GOOD.replace("# title", "# colour"), "line 2", "unknown header key"),
        (GOOD.replace("114.3", "60.3"), "line 8, column 'od'", "same OD"),
        # the same size spelled twice: a hint "4" would match either row
        (GOOD.replace("2,60.3", "4.0,60.3"), "line 8, column 'nominal'", "repeats line 7"),
        # millimetre numbers under "units: m": 60,300 mm pipes, to which nothing would snap
        (GOOD.replace("# units: mm", "# units: m"), "line 7, column 'od'", "is no pipe's"),
    ],
)
def test_malformed_catalog_names_file_line_and_column(tmp_path, text, where, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(CatalogError) as info:
        load_catalog(str(path))
    line = str(info.value)
    assert line.startswith(f"{path}: {where}: ")
    assert message in line
    assert "\n" not in line


def test_unknown_catalog_name_and_missing_file(tmp_path):
    with pytest.raises(CatalogError, match="unknown catalog 'nope'; use one of"):
        load_catalog("nope")
    with pytest.raises(CatalogError, match="not found"):
        load_catalog(str(tmp_path / "missing.csv"))


def test_parse_catalog_needs_a_table():
    with pytest.raises(CatalogError, match="no table"):
        parse_catalog("# name: x\n# kind: pipe\n# units: mm\n", source="x.csv")


def test_lookup_errors():
    cat = load_catalog("asme-b36.10m")
    with pytest.raises(KeyError):
        cat.size("7")
    assert cat.wall("22", "40") is None  # B36.10M lists no schedule 40 at NPS 22
    assert cat.label("4") == "NPS 4"
    assert [s.nominal for s in cat.nearest(0.110)] == ["4", "3 1/2"]


def test_loaded_catalogs_are_read_only_and_cached():
    cat = load_catalog("asme-b36.10m")
    assert load_catalog("asme-b36.10m") is cat
    with pytest.raises(TypeError):
        cat.size("4").walls["STD"] = 1.0  # type: ignore[index]
    with pytest.raises(TypeError):
        cat.fitting(cat.size("4")).dims["tee_run"] = 1.0  # type: ignore[index]


def test_short_radius_has_no_45_degree_elbow_so_the_long_radius_45_stands_in():
    """ASME B16.9 has no short-radius 45 degree elbow (standards reference): B = 64 mm at NPS 4."""
    steel = load_catalog("asme-b36.10m")
    four = steel.size("4")
    short = fitting_dims(steel, four, four.od, "short")
    assert short.bend_radius == pytest.approx(0.102)  # the 90 degree SR elbow stays
    assert short.elbow45_end == pytest.approx(0.064)
    assert "no short-radius 45 degree elbow" in short.elbow45_notes[0]
    long = fitting_dims(steel, four, four.od, "long")
    assert long.elbow45_end == pytest.approx(0.064) and long.elbow45_notes == ()
    # without a fittings table: the long-radius rule 1.5 x NPS, B = R tan(22.5 degrees)
    copper = load_catalog("astm-b88")
    two = copper.size("2")
    ruled = fitting_dims(copper, two, two.od, "short")
    assert ruled.elbow45_end == pytest.approx(1.5 * 2 * 0.0254 * math.tan(math.radians(22.5)))


_PIPES = """# name: my-pipes
# kind: pipe
# units: mm
# fittings: {fittings}
nominal,od,source
4,114.3,test
6,168.3,test
"""


@pytest.mark.parametrize(
    "files, message",
    [
        (
            {"my.csv": "my.csv"},
            "header 'fittings': 'my.csv' is a pipe catalog, not a fittings catalog",
        ),
        (
            {"my.csv": "other.csv", "other.csv": "my.csv"},
            "header 'fittings': 'other.csv' is a pipe catalog, not a fittings catalog",
        ),
    ],
    ids=["names-itself", "two-name-each-other"],
)
def test_a_fittings_cycle_is_one_located_line(tmp_path, files, message):
    # found by fuzzing user catalogs: a pipe catalog naming itself (or another pipe catalog
    # naming it back) as its fittings recursed until RecursionError
    for name, fittings in files.items():
        (tmp_path / name).write_text(_PIPES.format(fittings=fittings), encoding="utf-8")
    with pytest.raises(CatalogError) as info:
        load_catalog(str(tmp_path / "my.csv"))
    assert str(info.value) == f"{tmp_path / 'my.csv'}: {message}"


def test_a_fittings_name_too_long_for_the_system_is_one_located_line(tmp_path):
    # found by fuzzing user catalogs: a 300-character 'fittings' name made is_file() raise
    # OSError (File name too long) instead of answering False
    name = "asme-b16.9" + "0" * 300
    (tmp_path / "my.csv").write_text(_PIPES.format(fittings=name), encoding="utf-8")
    with pytest.raises(CatalogError) as info:
        load_catalog(str(tmp_path / "my.csv"))
    assert str(info.value).startswith(
        f"{tmp_path / 'my.csv'}: header 'fittings': unknown fittings catalog 'asme-b16.9000"
    )


LONG = "9" * 5000  # a pasted cell or a spreadsheet's runaway column


@pytest.mark.parametrize(
    ("text", "where"),
    [
        (GOOD.replace("114.3", LONG + "x"), "line 8, column 'od'"),  # not a number
        (
            GOOD.replace("nominal,od,", "nominal,nps,od,").replace("2,60", "2,x" + LONG + ",60"),
            "line 7, column 'nps'",
        ),
        (
            GOOD.replace("2,60.3", LONG + ",60.3").replace("4,114.3", LONG + ",114.3"),
            "line 8, column 'nominal'",
        ),  # repeats
        (GOOD.replace("wall_std", "c" + LONG), "line 6, column 'c" + "9" * 39 + "...' (5,001"),
        (GOOD.replace("# title", "# t" + LONG), "line 2"),  # unknown header key
        (GOOD.replace("# kind: pipe", "# kind: " + LONG), "header 'kind'"),
        (GOOD.replace("# units: mm", "# units: " + LONG), "header 'units'"),
        (GOOD.replace("# units: mm", "# units: mm\n# fittings: x" + LONG), "header 'fittings'"),
    ],
    ids=["cell", "nps", "nominal", "column", "header-key", "kind", "units", "fittings"],
)
def test_a_long_value_is_quoted_shortened_with_its_length(tmp_path, text, where):
    path = tmp_path / "long.csv"
    path.write_text(text)
    with pytest.raises(CatalogError) as info:
        load_catalog(str(path))
    line = str(info.value)
    assert line.startswith(f"{path}: {where}")
    assert "characters)" in line and "9" * 41 not in line
    assert len(line) < len(str(path)) + 250


def test_a_long_catalog_name_is_quoted_shortened():
    with pytest.raises(CatalogError) as info:
        load_catalog("n" * 5000)
    assert str(info.value).startswith("unknown catalog '" + "n" * 40 + "...' (5,000 characters)")


def test_a_folder_named_without_a_slash_is_said_to_be_a_folder(tmp_path, monkeypatch):
    """``--catalog mycat`` where mycat is a folder: "is a directory", not "unknown catalog";
    a shipped catalog's name still names the shipped catalog when a folder has it too."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mycat").mkdir()
    (tmp_path / "asme-b36.10m").mkdir()
    with pytest.raises(CatalogError, match=r"mycat: is a directory; give the catalog itself"):
        load_catalog("mycat")
    assert load_catalog("asme-b36.10m").name == "asme-b36.10m"
