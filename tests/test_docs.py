"""Documentation that is generated from code stays in step with it."""

from pathlib import Path

from chainmodel.parameters import markdown_table

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_parameter_table_is_current():
    text = (DOCS / "parameters.md").read_text()
    begin, end = "<!-- BEGIN GENERATED PARAMETERS -->\n", "<!-- END GENERATED PARAMETERS -->"
    assert begin in text and end in text
    table = text.split(begin, 1)[1].split(end, 1)[0]
    assert table == markdown_table(), "regenerate docs/parameters.md (python -m chainmodel.parameters)"
