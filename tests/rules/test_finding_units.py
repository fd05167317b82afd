"""Findings tell lengths in the model's display units: inches (and feet from 10 m) for a scan in
inches or feet, as the fits' notes do; millimetres and metres, unchanged, for a metric one. The
structured values (measured, allowed, stderr, unit, the suggestions' changes) stay SI."""

from __future__ import annotations

import re

import numpy as np
import pytest
from rules_builders import B36, model, pipe

from asbuilt.rules import check_model, load_rules
from asbuilt.scan.model import Scan, ScanObject

#: A length said in a message: a number and its unit.
LENGTH = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?) (mm|m|in|ft)\b")
#: A clash's overlap volume and its standard error.
VOLUME = re.compile(r"(\d+(?:\.\d+)?) (cm3|in3) \(\+- (\d+(?:\.\d+)?)\)")
#: Metres per unit said.
METRES = {"mm": 0.001, "m": 1.0, "in": 0.0254, "ft": 0.3048}


def lengths(text: str) -> list[tuple[float, str]]:
    return [(float(n), u) for n, u in LENGTH.findall(text)]


def defective_model(units: str):
    """Pipes with a size no catalog makes (AB101), a hint three sizes off (AB103), contiguous
    pipes of two sizes (AB104) and two crossing pipes (clash), in display units ``units``."""
    components = (
        pipe("P3", [0, 0, 1], [2, 0, 1], 0.1182, status="no-size"),
        pipe("H1", [0, 5, 1], [2, 5, 1], 0.1143),
        pipe("C1", [0, 10, 1], [2, 10, 1], 0.1143, nominal="4", od_fit=0.1146, status="snapped"),
        pipe(
            "C2",
            [2.05, 10, 1],
            [4, 10, 1],
            0.0889,
            nominal="3",
            od_fit=0.1010,
            status="snapped",
            od_stderr=0.005,
        ),
        pipe("X1", [0, 15, 1], [2, 15, 1], 0.1143, nominal="4", status="snapped"),
        pipe("X2", [1, 14, 1], [1, 16, 1], 0.1143, nominal="4", status="snapped"),
    )
    hint = ScanObject(id="H1", kind="cylinder", points=np.zeros((7, 3)), nominal='2"')
    scan = Scan(units=units, objects=(hint,))
    return model(*components, scan=scan).replace(units=units)


def findings(units: str):
    found = check_model(defective_model(units), load_rules(), catalog=B36)
    return {(f.slug, f.objects): f for f in found}


WANTED = ("nonstandard-diameter", "hint-mismatch", "contiguous-diameter-mismatch", "clash")


def test_the_defective_model_has_the_findings_people_read_most():
    slugs = {slug for slug, _ in findings("mm")}
    assert set(WANTED) <= slugs


@pytest.mark.parametrize("units", ["in", "ft"])
def test_an_imperial_models_findings_say_inches(units):
    metric, imperial = findings("mm"), findings(units)
    assert metric.keys() == imperial.keys()
    said = 0
    for key, f in metric.items():
        g = imperial[key]
        texts = [(f.message, g.message)] + [
            (s.description, t.description) for s, t in zip(f.suggestions, g.suggestions)
        ]
        for text_mm, text_in in texts:
            assert not re.search(r"\d (mm|m)\b", text_in), text_in
            pairs = list(zip(lengths(text_mm), lengths(text_in), strict=True))
            for (value, unit), (told, told_unit) in pairs:
                assert unit in ("mm", "m") and told_unit == "in"  # all under 10 m here
                metres = value * METRES[unit]
                # the inch value is the mm value / 25.4, to the 3 digits told (and the mm
                # value's own rounding to 0.1 mm)
                assert told == pytest.approx(metres / 0.0254, rel=5e-3, abs=0.003), text_in
                said += 1
            # the same sentence with its numbers left out
            assert LENGTH.sub("#", VOLUME.sub("#", text_mm)) == LENGTH.sub(
                "#", VOLUME.sub("#", text_in)
            )
        # the data stay SI
        assert (g.measured, g.allowed, g.stderr, g.unit) == (
            f.measured,
            f.allowed,
            f.stderr,
            f.unit,
        )
        assert [s.change for s in g.suggestions] == [s.change for s in f.suggestions]
    assert said >= 10


def test_nonstandard_diameter_in_inches():
    (f,) = [f for (slug, _), f in findings("in").items() if slug == "nonstandard-diameter"]
    assert f.message == (
        "OD 4.65 in +- 0.0197 in is no ASME B36.10M size (nearest NPS 4 = 4.5 in, 0.154 in off; "
        "a size is taken within the 0.0787 in diameter tolerance)"
    )
    assert f.measured == pytest.approx(0.0039) and f.unit == "m"


@pytest.mark.parametrize("units", ["m", "mm", "cm"])
def test_a_metric_models_findings_stay_millimetres(units):
    found = findings(units)
    (f,) = [f for (slug, _), f in found.items() if slug == "nonstandard-diameter"]
    assert f.message == (
        "OD 118.2 mm +- 0.5 mm is no ASME B36.10M size (nearest NPS 4 = 114.3 mm, 3.9 mm off; "
        "a size is taken within the 2.0 mm diameter tolerance)"
    )
    for g in found.values():
        assert not re.search(r"\d (in|ft)\b", g.message)
    assert [g.message for g in found.values()] == [g.message for g in findings("m").values()]


def test_a_clash_volume_in_cubic_inches():
    metric, imperial = findings("mm"), findings("in")
    key = ("clash", ("X1", "X2"))
    (cm3, unit, se), (in3, unit_in, se_in) = (
        VOLUME.search(metric[key].message).groups(),
        VOLUME.search(imperial[key].message).groups(),
    )
    assert (unit, unit_in) == ("cm3", "in3")
    cubic_inch = 2.54**3  # cm3
    assert float(in3) == pytest.approx(float(cm3) / cubic_inch, rel=5e-3)
    assert float(se_in) == pytest.approx(float(se) / cubic_inch, rel=0.05)
    assert imperial[key].unit == "m3" and imperial[key].measured == metric[key].measured
