"""Every numeric value of the rules file is checked against its meaningful range when loaded.

A ``pipe_ratio = 0`` used to crash ``asbuilt check`` with a ZeroDivisionError traceback (exit 1,
new-user audit). The bad values below are written by hand from what each option means (docs/
rules.md, asbuilt/tolerances.py), not taken from the range table, and a completeness test makes
sure every numeric key of the shipped schema is among them.
"""

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

from asbuilt.errors import RulesConfigError
from asbuilt.rules import loads_rules
from asbuilt.rules.config import _shipped
from asbuilt.tolerances import DEFAULT_TOLERANCES

REPO = Path(__file__).resolve().parents[2]

# (table, key) -> out-of-range values (TOML literals) and in-range boundary values.
CASES = {
    ("general", "k_sigma"): (["-1", "-0.5"], ["0", "3"]),
    ("general", "outlier_cutoff_sigma"): (["0", "-3"], ["2.5"]),
    ("general", "max_outlier_fraction"): (["-0.1", "0.5", "1", "1.2"], ["0", "0.3"]),
    ("general", "sigma_floor"): (["0", "-1e-4"], ["1e-5"]),
    ("general", "min_noise_dof"): (["0", "-2"], ["1", "8"]),
    ("general", "prior_range_sigma"): (["0", "-0.002"], ["0.003"]),
    ("general", "normal_neighbours"): (["1", "0", "-6"], ["2", "8"]),
    ("general", "face_angle_deg"): (["0", "90", "120", "-20"], ["30"]),
    ("general", "recommended_points_cylinder"): (["0", "-20"], ["1", "40"]),
    ("general", "recommended_points_cuboid"): (["0", "-30"], ["1", "40"]),
    ("general", "angle_snap_deg"): (["-1", "45"], ["0", "1.5"]),
    ("general", "angle_snap_max_deg"): (["-1", "45"], ["0", "5"]),
    ("general", "intended_angle_deg"): (["0", "-10", "45", "90"], ["5", "30"]),
    ("general", "diameter_tolerance"): (["-0.002"], ["0", "0.003"]),
    ("general", "joint_distance"): (["-0.15"], ["0", "0.3"]),
    ("general", "plate_thickness"): (["0", "-0.01"], ["0.02"]),
    ("nonstandard-diameter", "suggest"): (["0", "-2"], ["1", "5"]),
    ("out-of-plumb", "steel_ratio"): (["0", "-500", "0.002"], ["1", "1000"]),
    ("out-of-plumb", "pipe_ratio"): (["0", "-500", "0.5"], ["1", "200"]),
    ("out-of-plumb", "tank_ratio"): (["0", "-200", "0.005"], ["1", "500"]),
    ("out-of-plumb", "concrete_fraction"): (["0", "-0.003", "1.5", "333"], ["1", "0.005"]),
    ("out-of-plumb", "concrete_max"): (["0", "-0.025"], ["0.05"]),
    ("slope", "required"): (["-0.01", "1", "2"], ["0", "0.02"]),
    ("joint-gap", "tolerance"): (["-0.003"], ["0", "0.005"]),
    ("too-few-points", "sphere"): (["0", "-12"], ["1", "20"]),
    ("too-few-points", "plane"): (["0", "-10"], ["1", "20"]),
    ("too-few-points", "hull"): (["0", "-12"], ["1", "20"]),
    ("weak-geometry", "min_arc_deg"): (["-1", "361"], ["0", "360", "120"]),
    ("weak-geometry", "min_length_over_diameter"): (["-1"], ["0", "2"]),
    ("weak-geometry", "min_faces"): (["0", "-1", "7"], ["1", "6"]),
    ("weak-geometry", "max_relative_stderr"): (["0", "-0.05"], ["0.1"]),
    ("poor-fit", "max_rms_ratio"): (["0", "-2"], ["3"]),
    ("outliers", "max_share"): (["-0.2", "1.5"], ["0", "1", "0.3"]),
    ("clash", "min_volume"): (["-1e-6"], ["0", "1e-5"]),
    ("clash", "samples"): (["0", "-4096"], ["1", "1024"]),
    ("clash", "touch_distance"): (["-0.001"], ["0", "0.002"]),
    ("design-deviation", "length_tolerance_above"): (["-0.006"], ["0", "0.01"]),
    ("design-deviation", "position_tolerance"): (["-0.025"], ["0", "0.05"]),
    ("design-deviation", "direction_tolerance_deg"): (["-1", "91"], ["0", "90", "2"]),
    ("design-deviation", "section_plus"): (["-0.01"], ["0", "0.02"]),
    ("design-deviation", "section_minus"): (["-0.006"], ["0", "0.02"]),
    ("missing-component", "match_radius"): (["0", "-0.5"], ["1"]),
    ("design-deviation", "length_tolerance"): (
        ["[]", "[[10.0]]", "[[0, 0.003]]", "[[10, -0.003]]", "[[24, 0.005], [10, 0.003]]"],
        ["[[12, 0.004]]", "[[10, 0], [24, 0.005]]"],
    ),
}


def _numeric_keys():
    """Every (table, key) of the schema whose value is a number (or rows of numbers)."""
    shipped = _shipped()
    keys = set()
    for table, values in shipped.items():
        if not isinstance(values, dict):
            continue
        for key, value in values.items():
            if isinstance(value, (int, float, list)) and not isinstance(value, bool):
                if isinstance(value, list) and not (value and isinstance(value[0], list)):
                    continue  # lists of words
                keys.add((table, key))
    for f in dataclasses.fields(DEFAULT_TOLERANCES):
        keys.add(("general", f.name))
    return keys


def _text(table, key, literal):
    return f"[{table}]\n{key} = {literal}\n"


def test_every_numeric_key_has_bad_values_here():
    assert _numeric_keys() == set(CASES)


def test_the_shipped_defaults_load_and_are_in_range():
    config = loads_rules("")
    for table, key in CASES:
        if table == "general":
            value = config.general[key]
        else:
            value = config.option(table, key)
        # writing the default explicitly is accepted
        literal = repr(value) if not isinstance(value, list) else str(value)
        loads_rules(_text(table, key, literal), source="r.toml")


def _bad_cases():
    for (table, key), (bad, _) in CASES.items():
        for literal in bad:
            yield table, key, literal
        integer = isinstance(
            _shipped().get(table, {}).get(key, getattr(DEFAULT_TOLERANCES, key, None)), int
        )
        if key != "length_tolerance":
            # non-finite values TOML allows, and the wrong type
            yield table, key, "nan"
            yield table, key, "inf"
            yield table, key, "-inf"
            yield table, key, '"5"'
            yield table, key, "true"
            if integer:
                yield table, key, "2.5"


@pytest.mark.parametrize("table, key, literal", list(_bad_cases()))
def test_out_of_range_value_is_one_line_naming_file_key_value_and_range(table, key, literal):
    with pytest.raises(RulesConfigError) as err:
        loads_rules(_text(table, key, literal), source="project.toml")
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"project.toml: [{table}].{key}")
    assert "must be" in message
    value = tomllib.loads(f"x = {literal}")["x"]
    assert message.endswith(f"not {value!r}")


@pytest.mark.parametrize(
    "table, key, literal",
    [(t, k, lit) for (t, k), (_, good) in CASES.items() for lit in good],
)
def test_in_range_values_are_accepted(table, key, literal):
    config = loads_rules(_text(table, key, literal), source="project.toml")
    got = config.general[key] if table == "general" else config.option(table, key)
    if key != "length_tolerance":
        assert math.isclose(got, float(literal))


def test_range_is_named_in_the_message():
    with pytest.raises(RulesConfigError) as err:
        loads_rules("[out-of-plumb]\npipe_ratio = 0\n", source="bad.toml")
    assert str(err.value) == (
        "bad.toml: [out-of-plumb].pipe_ratio: must be a number at least 1 "
        "(1 in N of the height, e.g. 500), not 0"
    )
    with pytest.raises(RulesConfigError, match=r"greater than 0 and at most 1"):
        loads_rules("[out-of-plumb]\nconcrete_fraction = 0\n", source="bad.toml")
    with pytest.raises(RulesConfigError, match=r"an integer at least 1 .*not 0$"):
        loads_rules("[clash]\nsamples = 0\n", source="bad.toml")


def test_snap_band_must_lie_inside_the_intended_band():
    with pytest.raises(RulesConfigError, match=r"\[general\]\.angle_snap_deg.*intended_angle_deg"):
        loads_rules("[general]\nangle_snap_deg = 12\n", source="bad.toml")
    config = loads_rules("[general]\nangle_snap_deg = 12\nintended_angle_deg = 20\n")
    assert config.tolerances.angle_snap_deg == 12.0


@pytest.mark.parametrize("text", ["[out-of-plumb]\npipe_ratio = 0\n", "[clash]\nsamples = -1\n"])
def test_cli_exits_2_with_one_line(tmp_path, text):
    rules = tmp_path / "bad.toml"
    rules.write_text(text, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "check", "samples/plant.json", "--rules", str(rules)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert str(rules) in lines[0] and "must be" in lines[0] and "Traceback" not in done.stderr
