"""equiv --html: one self-contained page of evidence. The page of an equivalent run shows the verdict, every run and
every source file with its coverage; the page of a deliberately broken ST shows the divergence at its cycle, as a
timeline of both sides, with the source and ST lines that write the operand. The page needs nothing from outside
(no script, no link, no remote resource). Where Chromium is installed, a headless browser renders the page and the
test reads the DOM it built (the plot and the marked cycle are there)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from lxml import html as lxml_html

from transpiler.cli import main

ROOT = Path(__file__).resolve().parents[1]
EDGES = ROOT / "samples" / "constructs" / "edges"
PROGRAM = "L I0\nA I1\n= O3\nL I2\n= O4\nEM\n"
SCENARIO = ("cycles: 12\nevents:\n  - cycle: 2\n    set: {I0: 1}\n  - cycle: 5\n    set: {I1: 1}\n"
            "  - cycle: 8\n    set: {I2: 1}\n")


def _page(folder: Path) -> lxml_html.HtmlElement:
    return lxml_html.fromstring((folder / "index.html").read_bytes())


def _self_contained(text: str) -> None:
    assert "<script" not in text.lower()
    assert not re.search(r"""(src|href)\s*=\s*["'](https?:|//)""", text, re.I)
    assert "<link" not in text.lower()


def test_equivalent_run_page_shows_verdict_runs_and_coverage(tmp_path, capsys):
    out = tmp_path / "proof"
    assert main(["equiv", str(EDGES), "--scenario", str(EDGES / "scenario.yaml"), "--random-cycles", "100",
                 "--html", str(out)]) == 0
    assert f"reports: {out / 'index.html'}" in capsys.readouterr().out
    page = _page(out)
    assert page.get_element_by_id("verdict").text_content() == "EQUIVALENT"
    assert len(page.find_class("run")) == 2
    files = [h.get("data-path") for h in page.find_class("file")]
    assert files == ["main.src"]
    lines = page.find_class("line")
    assert len(lines) == len((EDGES / "main.src").read_text().splitlines())
    assert any("covered" in line.get("class").split() for line in lines)
    assert not page.find_class("divergence")
    _self_contained((out / "index.html").read_text())


def test_broken_translation_page_marks_the_divergence(tmp_path, capsys):
    (tmp_path / "main.src").write_text(PROGRAM)
    (tmp_path / "s.yaml").write_text(SCENARIO)
    assert main(["transpile", str(tmp_path / "main.src"), "--out", str(tmp_path / "out"), "--format", "st"]) == 0
    st = (tmp_path / "out" / "project.st").read_text()
    # The translation's AND becomes OR: O3 comes on at cycle 2 where the original waits for I1 (cycle 5).
    broken = re.sub(r"(O3\w* := \w+) AND ", r"\1 OR ", st, count=1)
    assert broken != st
    (tmp_path / "broken.st").write_text(broken)
    capsys.readouterr()
    out = tmp_path / "proof"
    assert main(["equiv", str(tmp_path / "main.src"), "--scenario", str(tmp_path / "s.yaml"), "--st",
                 str(tmp_path / "broken.st"), "--io-map", str(tmp_path / "out" / "io_map.csv"), "--no-shrink",
                 "--html", str(out)]) == 1
    printed = capsys.readouterr().out
    cycle = int(re.search(r"DIVERGENCE in s at cycle (\d+)", printed).group(1))
    assert cycle == 2
    page = _page(out)
    assert page.get_element_by_id("verdict").text_content() == "NOT EQUIVALENT"
    [article] = page.find_class("divergence")
    assert article.get("data-cycle") == "2" and article.get("data-operand") == "O3"
    [marker] = article.find_class("divergence-marker")
    assert marker.get("data-cycle") == "2"
    assert article.find_class("original") and article.find_class("translated")
    assert "main.src:3:1" in article.find_class("source-lines")[0].text_content()
    assert " OR " in article.find_class("st-lines")[0].text_content()
    inputs = article.find_class("inputs")[0].text_content()
    assert "I0" in inputs
    line3 = page.get_element_by_id("main-src-L3")
    assert "diverges" in line3.get("class").split()
    _self_contained((out / "index.html").read_text())


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium: the page is not rendered in a browser (`apt-get install "
                                              "chromium` runs it)")
def test_a_browser_renders_the_divergence(tmp_path, capsys):
    test_broken_translation_page_marks_the_divergence(tmp_path, capsys)
    page = (tmp_path / "proof" / "index.html").resolve()
    dom = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom", page.as_uri()],
                         capture_output=True, text=True, timeout=120, check=True).stdout
    rendered = lxml_html.fromstring(dom)
    [article] = rendered.find_class("divergence")
    assert article.get("data-cycle") == "2"
    assert rendered.xpath("//*[local-name()='svg']//*[local-name()='polyline']")
    shot = tmp_path / "proof.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                    "--window-size=1200,900", page.as_uri()], capture_output=True, timeout=120, check=True)
    assert shot.stat().st_size > 10_000


def test_mutate_page_shows_survivors_at_their_source_lines(tmp_path, capsys):
    (tmp_path / "main.src").write_text(PROGRAM)
    # Only I0 ever changes: the mutants of the I1 and I2 paths survive.
    (tmp_path / "weak.yaml").write_text("cycles: 4\nevents:\n  - cycle: 1\n    set: {I0: 1}\n")
    out = tmp_path / "proof"
    code = main(["mutate", str(tmp_path / "main.src"), "--scenario", str(tmp_path / "weak.yaml"), "--random-cycles",
                 "0", "--jobs", "1", "--backend", "builtin", "--html", str(out)])
    assert code == 1
    printed = capsys.readouterr().out
    survived = len([line for line in printed.splitlines() if line.startswith("SURVIVED: ")])
    assert survived >= 1
    page = _page(out)
    assert page.get_element_by_id("verdict").text_content().startswith("score ")
    assert "fail" in page.get_element_by_id("verdict").get("class").split()
    assert len(page.xpath("//tr[@class='survivor']")) == survived
    marked = [row for row in page.find_class("line") if "survivor" in row.get("class").split()]
    assert marked and all(row.find_class("note")[0].text_content().startswith("mutant survived") for row in marked)
    _self_contained((out / "index.html").read_text())


def test_a_report_folder_that_cannot_be_written_is_an_error_not_a_traceback(tmp_path, capsys):
    (tmp_path / "main.src").write_text(PROGRAM)
    (tmp_path / "s.yaml").write_text(SCENARIO)
    blocked = tmp_path / "a_file"
    blocked.write_text("not a folder")
    code = main(["equiv", str(tmp_path / "main.src"), "--scenario", str(tmp_path / "s.yaml"), "--html", str(blocked)])
    err = capsys.readouterr().err
    assert code == 2 and "error[E-TOOL]: cannot write the reports" in err and "Traceback" not in err
    assert blocked.read_text() == "not a folder"
