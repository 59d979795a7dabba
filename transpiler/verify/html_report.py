"""One self-contained HTML page that shows the evidence of an equivalence check (or a mutation run) where a reviewer
looks: the verdict and every run, each divergence as a timeline of the operand on both sides with the inputs that
changed before it and the source and ST lines that write it, and every source file with its covered, partly covered
and never executed lines (and, for mutate, the surviving mutants at the lines they come from). No script, no
network: inline CSS and SVG only, so the page opens from a CI artifact as it is."""

from __future__ import annotations

import dataclasses
import html
import re
from typing import Iterable, Mapping, Sequence

from transpiler.verify.divergence_trace import DivergenceTrace

PAGE_FILE = "index.html"
# Lines as the front end counts them (a form feed or a Unicode line separator is no line break there).
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
PLOT_WIDTH, PLOT_HEIGHT, PLOT_MARGIN = 720, 150, 40

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;max-width:1200px}
h1{font-size:1.4em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ccc}h3{font-size:1em}
.verdict{padding:.1em .5em;border-radius:.3em;color:#fff}.verdict.pass{background:#2e7d32}.verdict.fail{background:#c62828}
table{border-collapse:collapse;font-size:.9em}td,th{padding:.15em .6em;border-bottom:1px solid #eee;text-align:left}
table.src{font-family:ui-monospace,monospace;font-size:.82em;width:100%}table.src td{border:0;white-space:pre}
tr.covered td.code{background:#e8f5e9}tr.partial td.code{background:#fff8e1}tr.uncovered td.code{background:#ffebee}
tr.diverges td.code{outline:2px solid #c62828}tr.survivor td.code{background:#f3e5f5}
td.num,td.hits,td.branches{color:#888;text-align:right}td.note{color:#6a1b9a;font-family:system-ui,sans-serif;white-space:normal}
.side{display:flex;gap:2em}.side>div{flex:1;min-width:0}pre{background:#f7f7f7;padding:.5em;overflow-x:auto}
svg text{font-size:11px;font-family:system-ui,sans-serif}.legend span{margin-right:1.5em}
"""


@dataclasses.dataclass(frozen=True)
class RunRow:
    name: str
    status: str            # equivalent, DIVERGENCE, FAULT, MISSING, ...
    cycles: int
    compared: int
    seconds: float


@dataclasses.dataclass(frozen=True)
class SourceLine:
    number: int
    text: str
    hits: int | None               # None: no instruction on the line
    branches: tuple[int, int] = (0, 0)     # (taken, outcomes)
    notes: tuple[str, ...] = ()    # surviving mutants made from this line, divergence marks


@dataclasses.dataclass(frozen=True)
class SourceFile:
    path: str
    lines: tuple[SourceLine, ...]


@dataclasses.dataclass(frozen=True)
class Evidence:
    """Everything the page shows, already decided: the page only lays it out."""

    title: str
    verdict: str
    passed: bool
    summary: Sequence[str]                 # one sentence each: runs and cycles, coverage, score
    runs: Sequence[RunRow] = ()
    divergences: Sequence[DivergenceTrace] = ()
    sources: Sequence[SourceFile] = ()
    survivors: Sequence[tuple[str, str, str]] = ()     # (source line or '', ST location, text) of surviving mutants


def render_page(evidence: Evidence) -> bytes:
    e = html.escape
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{e(evidence.title)}: {e(evidence.verdict)}</title><style>{_STYLE}</style></head><body>",
             f'<h1>{e(evidence.title)}: <span id="verdict" class="verdict {"pass" if evidence.passed else "fail"}">'
             f"{e(evidence.verdict)}</span></h1>"]
    parts += [f"<p>{e(sentence)}</p>" for sentence in evidence.summary]
    if evidence.divergences:
        parts.append('<h2 id="divergences">Divergences</h2>')
        parts += [_divergence(n, d) for n, d in enumerate(evidence.divergences)]
    if evidence.survivors:
        parts.append(f'<h2 id="survivors">Surviving mutants ({len(evidence.survivors)})</h2><table>'
                     "<tr><th>source</th><th>ST</th><th>mutant</th></tr>")
        parts += [f'<tr class="survivor"><td>{e(src)}</td><td>{e(st)}</td><td><code>{e(text)}</code></td></tr>'
                  for src, st, text in evidence.survivors]
        parts.append("</table>")
    if evidence.runs:
        parts.append(f'<h2 id="runs">Runs ({len(evidence.runs)})</h2><table><tr><th>run</th><th>result</th>'
                     "<th>cycles</th><th>operands compared</th><th>seconds</th></tr>")
        parts += [f'<tr class="run"><td>{e(r.name)}</td><td>{e(r.status)}</td><td>{r.cycles}</td><td>{r.compared}</td>'
                  f"<td>{r.seconds:.2f}</td></tr>" for r in evidence.runs]
        parts.append("</table>")
    if any(line.hits is not None for f in evidence.sources for line in f.lines):
        parts.append('<h2 id="sources">Source coverage</h2><p class="legend"><span style="background:#e8f5e9">'
                     'executed, every outcome taken</span><span style="background:#fff8e1">executed, an outcome '
                     'never taken</span><span style="background:#ffebee">never executed</span></p>')
        parts += [_source(f) for f in evidence.sources]
    elif evidence.sources:
        parts.append('<h2 id="sources">Source</h2>')
        parts += [_source(f) for f in evidence.sources]
    parts.append("</body></html>")
    return ("\n".join(parts) + "\n").encode("utf-8")


def _divergence(number: int, d: DivergenceTrace) -> str:
    e = html.escape
    head = (f'<article class="divergence" id="divergence-{number}" data-run="{e(d.run)}" data-cycle="{d.cycle}" '
            f'data-operand="{e(d.operand)}"><h3>{e(d.run)}: cycle {d.cycle}, {e(d.name)} ({e(d.operand)}): original '
            f"{e(str(d.original[-1]))}, translated {e(str(d.translated[-1]))}</h3>")
    replay = "" if d.replayed == d.run else f"<p>Replayed with its shrunk stimulus <code>{e(d.replayed)}</code>.</p>"
    inputs = "".join(f"<tr><td>{c}</td><td>{e(name)}</td><td>{e(str(value))}</td></tr>" for c, name, value in d.inputs)
    inputs += "".join(f"<tr><td>{c}</td><td>NC</td><td>{e(action)}</td></tr>" for c, action in d.nc)
    table = (f'<table class="inputs"><tr><th>cycle</th><th>input</th><th>value</th></tr>{inputs}</table>' if inputs
             else "<p>No input changed in these cycles.</p>")
    sources = "".join(f"<li><code>{e(s)}</code></li>" for s in d.source_lines) or "<li>(none found)</li>"
    st = "\n".join(f"{n}: {e(text)}" for n, text in d.st_lines) or "(no assignment found)"
    return (head + replay + timeline_svg(d) + table + '<div class="side"><div><h4>Source lines that write it</h4>'
            f'<ul class="source-lines">{sources}</ul></div><div><h4>ST lines that assign it</h4>'
            f'<pre class="st-lines">{st}</pre></div></div></article>')


def timeline_svg(d: DivergenceTrace) -> str:
    """Both sides' values of the operand as step lines over the cycles shown, the divergence cycle marked."""
    values = [_number(v) for v in (*d.original, *d.translated)]
    low, high = min(values), max(values)
    span = (high - low) or 1
    first, last = d.cycles[0], d.cycles[-1]
    width = PLOT_WIDTH - 2 * PLOT_MARGIN
    height = PLOT_HEIGHT - 2 * PLOT_MARGIN

    def x(cycle: float) -> float:
        return PLOT_MARGIN + (width * (cycle - first) / (last - first + 1))

    def y(value: float) -> float:
        return PLOT_MARGIN + height - height * (value - low) / span

    def steps(series: Iterable, dy: float) -> str:
        points = []
        for cycle, value in zip(d.cycles, series):
            level = y(_number(value)) + dy
            points += [f"{x(cycle):.1f},{level:.1f}", f"{x(cycle + 1):.1f},{level:.1f}"]
        return " ".join(points)
    marker = x(d.cycle)
    return (f'<svg class="timeline" width="{PLOT_WIDTH}" height="{PLOT_HEIGHT}" viewBox="0 0 {PLOT_WIDTH} '
            f'{PLOT_HEIGHT}" role="img" aria-label="{html.escape(d.name)} on both sides, cycles {first} to {last}">'
            f'<rect x="{PLOT_MARGIN}" y="{PLOT_MARGIN}" width="{width}" height="{height}" fill="#fafafa" '
            'stroke="#ddd"/>'
            f'<line class="divergence-marker" data-cycle="{d.cycle}" x1="{marker:.1f}" x2="{marker:.1f}" '
            f'y1="{PLOT_MARGIN - 8}" y2="{PLOT_MARGIN + height + 8}" stroke="#c62828" stroke-dasharray="4 3"/>'
            f'<polyline class="original" fill="none" stroke="#1565c0" stroke-width="2" points="{steps(d.original, 0)}"/>'
            f'<polyline class="translated" fill="none" stroke="#ef6c00" stroke-width="2" stroke-dasharray="6 3" '
            f'points="{steps(d.translated, 2)}"/>'
            f'<text x="{PLOT_MARGIN}" y="{PLOT_HEIGHT - 12}">cycle {first}</text>'
            f'<text x="{PLOT_WIDTH - PLOT_MARGIN}" y="{PLOT_HEIGHT - 12}" text-anchor="end">cycle {last}</text>'
            f'<text x="{marker:.1f}" y="{PLOT_MARGIN - 12}" text-anchor="middle" fill="#c62828">cycle {d.cycle}</text>'
            f'<text x="{PLOT_MARGIN - 4}" y="{y(high) + 4:.1f}" text-anchor="end">{high:g}</text>'
            f'<text x="{PLOT_MARGIN - 4}" y="{y(low) + 4:.1f}" text-anchor="end">{low:g}</text>'
            f'<text x="{PLOT_MARGIN}" y="14" fill="#1565c0">original</text>'
            f'<text x="{PLOT_MARGIN + 70}" y="14" fill="#ef6c00">translated</text></svg>')


def _number(value: int | str) -> float:
    """A plotted value: numbers as they are, a string by its length (the plot shows that it changed)."""
    return float(value) if isinstance(value, (int, float)) else float(len(str(value)))


def _source(f: SourceFile) -> str:
    e = html.escape
    rows = []
    anchor = "".join(c if c.isalnum() else "-" for c in f.path)
    for line in f.lines:
        taken, outcomes = line.branches
        if line.hits is None:
            kind = "plain"
        elif not line.hits:
            kind = "uncovered"
        elif taken < outcomes:
            kind = "partial"
        else:
            kind = "covered"
        if any(note.startswith("divergence") for note in line.notes):
            kind += " diverges"
        if any(note.startswith("mutant") for note in line.notes):
            kind += " survivor"
        hits = "" if line.hits is None else str(line.hits)
        branches = f"{taken}/{outcomes}" if outcomes else ""
        notes = "; ".join(line.notes)
        rows.append(f'<tr class="line {kind}" id="{anchor}-L{line.number}" data-line="{line.number}">'
                    f'<td class="num">{line.number}</td><td class="hits">{hits}</td><td class="branches">{branches}'
                    f'</td><td class="code">{e(line.text)}</td><td class="note">{e(notes)}</td></tr>')
    return f'<h3 class="file" data-path="{e(f.path)}">{e(f.path)}</h3><table class="src">' + "".join(rows) + "</table>"


def source_files(texts: Mapping[str, str], coverage: Mapping[str, Mapping[int, tuple[int, int, int]]],
                 notes: Mapping[tuple[str, int], Sequence[str]] | None = None) -> tuple[SourceFile, ...]:
    """The files to list: `texts` path -> text, `coverage` path -> line -> (runs that executed it, outcomes taken,
    outcomes), `notes` (path, line) -> notes to show at the line."""
    notes = notes or {}
    files = []
    for path, text in texts.items():
        lines = coverage.get(path, {})
        parts = _LINE_BREAK.split(text)
        if parts and parts[-1] == "":
            parts.pop()                     # the break that ends the last line starts no line of its own
        files.append(SourceFile(path, tuple(
            SourceLine(n, line, lines[n][0] if n in lines else None, (lines[n][1], lines[n][2]) if n in lines
                       else (0, 0), tuple(notes.get((path, n), ())))
            for n, line in enumerate(parts, start=1))))
    return tuple(files)
