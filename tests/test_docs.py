"""The user documentation in docs/ stands alone and matches the code: every page is there, the assumption table
is the code's, every command-line option is documented, links resolve, and no message, comment or template cites
the internal language description instead of a docs/ page."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from transpiler.cli.app import build_parser
from transpiler.language.semantics import ASSUMPTIONS, PROFILES

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = ("getting-started", "cli", "scenarios", "language", "assumptions", "import", "ci", "modules", "api", "hh_lib", "masks")
# A citation of the internal reference ("spec 6.5", the file names of the language description) points users at a
# text they do not have; messages and generated comments point at docs/ pages instead.
SPEC_CITATION = re.compile(r"spec [0-9]+[a-z]?\.[0-9]+|spec (sections? )?[0-9]+[a-z]?\b|heidenhain-plc\.md|"
                           r"scenario-format\.md|shared/spec")
DOC_LINK = re.compile(r"docs/([A-Za-z0-9_-]+\.md)(#[A-Za-z0-9_-]+)?")
MD_LINK = re.compile(r"\]\(([^)#\s]*)(#[^)\s]+)?\)")


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[`*]", "", heading.strip().lower())
    return "#" + re.sub(r"[^a-z0-9 _-]", "", text).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    return {anchor(m.group(1)) for m in re.finditer(r"^#+ (.+)$", page.read_text(encoding="utf-8"), re.M)}


def _source_files() -> list[Path]:
    return sorted(p for folder in ("transpiler", "templates") for p in (ROOT / folder).rglob("*")
                  if p.is_file() and p.suffix in (".py", ".j2", ".lark", ".c", ".h"))


@pytest.mark.parametrize("page", PAGES)
def test_every_page_exists_and_has_a_title(page: str) -> None:
    text = (DOCS / f"{page}.md").read_text(encoding="utf-8")
    assert text.startswith("# ") and len(text) > 400


def test_the_assumption_table_is_the_codes() -> None:
    text = (DOCS / "assumptions.md").read_text(encoding="utf-8")
    header = next(line for line in text.splitlines() if line.startswith("| id |"))
    columns = [c.strip() for c in header.strip("|").split("|")]
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if line.startswith("| A-"):
            rows[cells[0]] = dict(zip(columns, cells))
    assert [a.id for a in ASSUMPTIONS] == list(rows), "one row per assumption, in the code's order"
    for a in ASSUMPTIONS:
        row = rows[a.id]
        assert row["key"] == f"`{a.key}`", a.id
        for name, profile in PROFILES.items():
            value = profile.defaults[a.key]
            shown = "(empty)" if value == "" else str(value).lower() if isinstance(value, bool) else str(value)
            assert row[name] == f"`{shown}`", (a.id, name)
        for alternative in a.alternatives:
            assert str(alternative).lower() in row["other values"].lower(), (a.id, alternative)


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_every_command_and_option_is_in_the_cli_page() -> None:
    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    parser = build_parser()
    assert "--version" in text
    for name, sub in _subparsers(parser).items():
        assert f"\n## {name}\n" in text, f"docs/cli.md has no section for `{name}`"
        for action in sub._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}" in text or f"{flag} " in text, f"docs/cli.md does not document {name} {flag}"
    for status in ("| 0 |", "| 1 |", "| 2 |"):
        assert status in text


def test_links_between_pages_resolve() -> None:
    for page in DOCS.glob("*.md"):
        for match in MD_LINK.finditer(page.read_text(encoding="utf-8")):
            target, fragment = match.group(1), match.group(2)
            if target.startswith(("http://", "https://")):
                continue
            path = (page.parent / target) if target else page
            assert path.exists(), f"{page.name}: link to missing {target}"
            if fragment and path.suffix == ".md":
                assert fragment in anchors(path), f"{page.name}: no heading {fragment} in {path.name}"


def test_no_citation_of_the_internal_language_description() -> None:
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in _source_files()
             for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
             if SPEC_CITATION.search(line)]
    assert not found, "point at a docs/ page (or state the rule) instead:\n" + "\n".join(found)


def _user_files() -> list[Path]:
    """What users read besides the code: the README, docs/ and the samples (sources, definitions, scenarios)."""
    return [ROOT / "README.md", *sorted(DOCS.glob("*.md")),
            *sorted(p for p in (ROOT / "samples").rglob("*") if p.is_file()
                    and p.suffix.lower() in (".md", ".src", ".def", ".cfg", ".mp", ".yaml"))]


def test_no_citation_of_the_internal_language_description_in_user_files() -> None:
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in _user_files()
             for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
             if SPEC_CITATION.search(line)]
    assert not found, "point at a docs/ page (or state the rule) instead:\n" + "\n".join(found)


def test_links_and_docs_references_in_the_samples_resolve() -> None:
    for path in _user_files():
        if ROOT / "samples" not in path.parents:
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        if path.suffix == ".md":
            for match in MD_LINK.finditer(text):
                target, fragment = match.group(1), match.group(2)
                if target.startswith(("http://", "https://")):
                    continue
                linked = (path.parent / target) if target else path
                assert linked.exists(), f"{path.relative_to(ROOT)}: link to missing {target}"
                if fragment and linked.suffix == ".md":
                    assert fragment in anchors(linked), f"{path.relative_to(ROOT)}: no heading {fragment}"
        else:
            for match in DOC_LINK.finditer(text):
                page = DOCS / match.group(1)
                assert page.is_file(), f"{path.relative_to(ROOT)} points at missing {match.group(0)}"
                if match.group(2):
                    assert match.group(2) in anchors(page), f"{path.relative_to(ROOT)}: no heading {match.group(0)}"


def test_every_docs_link_in_messages_and_comments_points_at_a_page_and_heading() -> None:
    seen = 0
    for path in _source_files():
        for match in DOC_LINK.finditer(path.read_text(encoding="utf-8", errors="replace")):
            seen += 1
            page = DOCS / match.group(1)
            assert page.is_file(), f"{path.relative_to(ROOT)} points at missing {match.group(0)}"
            if match.group(2):
                assert match.group(2) in anchors(page), f"{path.relative_to(ROOT)}: no heading for {match.group(0)}"
    assert seen > 0


def test_every_known_plc_module_is_in_the_modules_page() -> None:
    from transpiler.language.module_table import MODULE_TABLE
    text = (DOCS / "modules.md").read_text(encoding="utf-8")
    missing = [n for n in MODULE_TABLE if f"| {n} |" not in text]
    assert not missing, f"docs/modules.md lacks modules {missing}"
