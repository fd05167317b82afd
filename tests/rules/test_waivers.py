"""Waivers ([[waive]] in a rules file): accepted findings become info with their reason."""

import numpy as np
import pytest
from rules_builders import B36, column, model, pipe

from asbuilt.errors import RulesConfigError, SuggestionError
from asbuilt.findings import Waived
from asbuilt.rules import (
    apply_fixes,
    apply_suggestions,
    check_model,
    choose_suggestions,
    loads_rules,
)

LEANING = model(column("C4", [0, 0, 0], 0.3, 4.0, axes_deg=0.01))  # 21 mm over 4 m: an error
T = np.radians(5)
TILTED = pipe("P9", [0, 6, 1], [3 * np.cos(T), 6, 1 + 3 * np.sin(T)], 0.1143, nominal="4")


def rules(*entries):
    text = "".join(f'[[waive]]\nfinding = "{f}"\nreason = "{r}"\n' for f, r in entries)
    return loads_rules(text, source="project.toml")


def by_slug(findings, slug):
    return [f for f in findings if f.slug == slug]


def test_leaning_column_is_an_error_without_a_waiver():
    (lean,) = by_slug(check_model(LEANING, catalog=B36), "out-of-plumb")
    assert lean.severity == "error" and lean.suggestions


@pytest.mark.parametrize("key", ["AB202@C4", "out-of-plumb@C4", "ab202@C4"])
def test_a_waived_finding_is_info_with_its_reason_and_no_suggestions(key):
    config = rules((key, "accepted by the structural engineer, RFI-0123"))
    found = check_model(LEANING, config, catalog=B36)
    (lean,) = by_slug(found, "out-of-plumb")
    assert lean.severity == "info" and lean.suggestions == () and not lean.unverifiable
    assert lean.message.startswith(
        "waived (accepted by the structural engineer, RFI-0123); as an error: leans"
    )
    assert lean.measured is not None  # the measurement stays on record
    assert lean.waived == Waived("accepted by the structural engineer, RFI-0123", "error")
    assert not by_slug(found, "unused-waiver")


def test_a_waived_finding_says_so_in_the_model_document_and_reads_back():
    import jsonschema

    from asbuilt.export.model_json import (
        finding_to_dict,
        model_document,
        model_from_document,
        model_schema,
    )

    config = rules(("AB202@C4", "RFI-0123"))
    found = check_model(LEANING, config, catalog=B36)
    (lean,) = by_slug(found, "out-of-plumb")
    entry = finding_to_dict(lean)
    assert entry["waived"] == {"reason": "RFI-0123", "severity": "error"}
    assert (
        finding_to_dict(by_slug(check_model(LEANING, catalog=B36), "out-of-plumb")[0])["waived"]
        is None
    )
    schema = model_schema()
    validator = jsonschema.Draft202012Validator(
        {**schema["$defs"]["finding"], "$defs": schema["$defs"]}
    )
    assert list(validator.iter_errors(entry)) == []
    document = model_document(LEANING.replace(findings=tuple(found)))
    read = model_from_document(document)
    (back,) = by_slug(read.findings, "out-of-plumb")
    assert back.waived == lean.waived and back.severity == "info"


def test_fix_changes_nothing_a_waiver_accepts():
    built = model(TILTED)
    config = rules(("misaligned-axis@P9", "laid to fall on purpose"))
    found = check_model(built, config, catalog=B36)
    (tilt,) = by_slug(found, "misaligned-axis")
    assert tilt.severity == "info"
    fixed, changes = apply_fixes(built, found)
    assert changes == [] and fixed.components == built.components
    # a waived finding has nothing to accept; without the waiver its rotation can be accepted
    with pytest.raises(SuggestionError):
        choose_suggestions(found, ["misaligned-axis@P9"])
    chosen = choose_suggestions(check_model(built, catalog=B36), ["misaligned-axis@P9"])
    assert apply_suggestions(built, chosen)[1]


def test_an_unused_waiver_is_reported_when_its_rule_ran_on_its_objects():
    straight = model(column("C4", [0, 0, 0], 0.0, 4.0, axes_deg=0.01))
    config = rules(("AB202@C4", "RFI-0123"))
    (unused,) = by_slug(check_model(straight, config, catalog=B36), "unused-waiver")
    assert unused.code == "AB002" and unused.severity == "info" and unused.objects == ("C4",)
    assert unused.message.startswith("the waiver of AB202@C4 (RFI-0123) matches no finding")
    # the rule did not run: not unused
    quiet = config.with_selection(ignore=["out-of-plumb"])
    assert not by_slug(check_model(straight, quiet, catalog=B36), "unused-waiver")
    # another scan's object: passed over
    other = rules(("AB202@C9", "RFI-0456"))
    assert not by_slug(check_model(straight, other, catalog=B36), "unused-waiver")


def test_a_waiver_of_other_objects_leaves_the_finding():
    config = rules(("AB202@C5", "another column"))
    (lean,) = by_slug(check_model(LEANING, config, catalog=B36), "out-of-plumb")
    assert lean.severity == "error"


@pytest.mark.parametrize(
    "text, where, message",
    [
        ('waive = "AB202@C4"', "waive", "write each waiver as a [[waive]] table"),
        ('[[waive]]\nfinding = "AB202@C4"\n', "[[waive]] 1.reason", "missing; say why"),
        ('[[waive]]\nreason = "x"\n', "[[waive]] 1.finding", "missing; give the finding"),
        ('[[waive]]\nfinding = "AB202@C4"\nreason = " "\n', "[[waive]] 1.reason", "must be text"),
        ('[[waive]]\nfinding = 4\nreason = "x"\n', "[[waive]] 1.finding", "must be text, not '4'"),
        (
            '[[waive]]\nfinding = "AB202"\nreason = "x"\n',
            "[[waive]] 1.finding",
            "is no finding key",
        ),
        (
            '[[waive]]\nfinding = "AB9@C4"\nreason = "x"\n',
            "[[waive]] 1.finding",
            "is no finding key",
        ),
        (
            '[[waive]]\nfinding = "AB2@C4"\nreason = "x"\n',
            "[[waive]] 1.finding",
            "is no finding key",
        ),
        (
            '[[waive]]\nfinding = "AB001@X1"\nreason = "x"\n',
            "[[waive]] 1.finding",
            "a refused fit cannot be waived",
        ),
        (
            '[[waive]]\nfinding = "AB202@C4"\nreason = "x"\nby = "me"\n',
            "[[waive]] 1.by",
            "unknown option 'by'",
        ),
        (
            '[[waive]]\nfinding = "AB202@C4"\nreason = "x"\n'
            '[[waive]]\nfinding = "out-of-plumb@C4"\nreason = "y"\n',
            "[[waive]] 2.finding",
            "AB202@C4 is waived twice",
        ),
        (
            f'[[waive]]\nfinding = "AB202@C4"\nreason = "{"x" * 501}"\n',
            "[[waive]] 1.reason",
            "501 characters; keep a reason to 500",
        ),
    ],
)
def test_bad_waivers_are_one_line_errors(text, where, message):
    with pytest.raises(RulesConfigError) as info:
        loads_rules(text, source="project.toml")
    assert str(info.value).startswith(f"project.toml: {where}: ")
    assert message in str(info.value) and "\n" not in str(info.value)
