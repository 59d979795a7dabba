"""Coverage of the original source in the files CI tools read: Cobertura XML (GitLab's merge request diff, most
coverage actions) and LCOV tracefiles (genhtml, coverage services); file paths relative to the folder the check
runs in, as the repository checkout of a CI job is."""

from __future__ import annotations

from pathlib import Path, PurePath
from typing import Iterable, Mapping

from lxml import etree

import transpiler
from transpiler.backends.plcopen.writer import build_time
from transpiler.verify.source_coverage import FileCoverage, LineCoverage, SourceCoverage

LCOV_TEST_NAME = "hh2iec_equiv"


def report_base(main_dir: Path, cwd: Path) -> Path:
    """The folder the report's paths are relative to: the current folder when the project lies inside it (a CI job
    runs in the repository checkout, and GitLab and GitHub match paths relative to that), else the main program's."""
    main_dir, cwd = main_dir.resolve(), cwd.resolve()
    return cwd if main_dir == cwd or cwd in main_dir.parents else main_dir


def export_paths(paths: Iterable[str], main_dir: Path, base: Path) -> dict[str, str]:
    """Each source path as the program names it (relative to the main program's folder, or absolute) -> the path
    written to the reports: relative to `base` with forward slashes, absolute where the file lies outside it."""
    main_dir, base = main_dir.resolve(), base.resolve()
    result = {}
    for path in paths:
        absolute = main_dir / path          # an absolute `path` stays as it is
        try:
            result[path] = absolute.relative_to(base).as_posix()
        except ValueError:
            result[path] = absolute.as_posix()
    return result


def _rate(covered: int, valid: int) -> str:
    """A rate as Cobertura writes it: 0 to 1, four decimals at most, never in exponent notation; nothing to cover
    counts as all covered."""
    return f"{covered / valid:.4f}".rstrip("0").rstrip(".") if valid else "1"


def _percent(covered: int, valid: int) -> str:
    return f"{100 * covered // valid}%"     # rounded down: 100% only when every outcome was taken


def _line_element(parent: etree._Element, line: LineCoverage) -> None:
    element = etree.SubElement(parent, "line", number=str(line.number), hits=str(line.hits),
                               branch="true" if line.branches else "false")
    if not line.branches:
        return
    element.set("condition-coverage", f"{_percent(line.branches_covered, line.branches_valid)} "
                                      f"({line.branches_covered}/{line.branches_valid})")
    conditions = etree.SubElement(element, "conditions")
    for number, point in enumerate(line.branches):
        etree.SubElement(conditions, "condition", number=str(number), type=point.kind,
                         coverage=_percent(point.covered, len(point.taken)))


def _rates(element: etree._Element, figures) -> None:
    element.set("line-rate", _rate(figures.lines_covered, figures.lines_valid))
    element.set("branch-rate", _rate(figures.branches_covered, figures.branches_valid))


def cobertura_xml(coverage: SourceCoverage, paths: Mapping[str, str], source: str, *,
                  timestamp_ms: int | None = None) -> bytes:
    """The coverage as Cobertura XML (the coverage-04 DTD): a package per folder, a class per source file named
    by its path in `paths`, a line per source line with instructions; `hits` counts the runs that executed the
    line; a branching line has `condition-coverage` and a condition per branching instruction (`jump` for a
    conditional jump, call or module end, `switch` for a CASE). `source` is the folder the paths are relative to.
    The timestamp (milliseconds) is `timestamp_ms`, else $SOURCE_DATE_EPOCH, else now; deterministic otherwise."""
    if timestamp_ms is None:
        timestamp_ms = int(build_time().timestamp()) * 1000
    root = etree.Element("coverage", {
        "line-rate": _rate(coverage.lines_covered, coverage.lines_valid),
        "branch-rate": _rate(coverage.branches_covered, coverage.branches_valid),
        "lines-covered": str(coverage.lines_covered), "lines-valid": str(coverage.lines_valid),
        "branches-covered": str(coverage.branches_covered), "branches-valid": str(coverage.branches_valid),
        "complexity": "0", "version": transpiler.__version__, "timestamp": str(timestamp_ms)})
    root.addprevious(etree.Comment(f" hh2iec {transpiler.__version__} equiv: coverage of the HEIDENHAIN PLC source "
                                   f"by the reference interpreter, runs: {coverage.runs}; hits = runs that "
                                   f"executed the line (Cobertura coverage-04 DTD) "))
    etree.SubElement(etree.SubElement(root, "sources"), "source").text = source
    folders: dict[str, list[FileCoverage]] = {}
    for f in coverage.files:
        folders.setdefault(str(PurePath(paths[f.path]).parent.as_posix()), []).append(f)
    packages = etree.SubElement(root, "packages")
    for folder in sorted(folders):
        group = SourceCoverage(coverage.runs, tuple(folders[folder]))
        package = etree.SubElement(packages, "package", name=folder)
        _rates(package, group)
        package.set("complexity", "0")
        classes = etree.SubElement(package, "classes")
        for f in sorted(group.files, key=lambda f: paths[f.path]):
            element = etree.SubElement(classes, "class", name=PurePath(paths[f.path]).name, filename=paths[f.path])
            _rates(element, f)
            element.set("complexity", "0")
            etree.SubElement(element, "methods")
            lines = etree.SubElement(element, "lines")
            for line in f.lines:
                _line_element(lines, line)
    return etree.tostring(root.getroottree(), xml_declaration=True, encoding="UTF-8", pretty_print=True)


def lcov_text(coverage: SourceCoverage, paths: Mapping[str, str]) -> str:
    """The coverage as an LCOV tracefile: a record per source file (SF: its path in `paths`), DA:line,hits with
    hits = the runs that executed the line, BRDA:line,block,branch,taken for each outcome of a branching instruction
    (block = its place among the line's branching instructions; branch 0 falls through and 1 jumps, or the CASE
    entry; taken = the runs that took it, `-` when no run reached the instruction), then the BRF/BRH and LF/LH
    totals."""
    out: list[str] = []
    for f in sorted(coverage.files, key=lambda f: paths[f.path]):
        out += [f"TN:{LCOV_TEST_NAME}", f"SF:{paths[f.path]}"]
        for line in f.lines:
            for block, point in enumerate(line.branches):
                for branch, runs in enumerate(point.taken):
                    out.append(f"BRDA:{line.number},{block},{branch},{runs if point.runs else '-'}")
        out += [f"BRF:{f.branches_valid}", f"BRH:{f.branches_covered}"]
        out += [f"DA:{line.number},{line.hits}" for line in f.lines]
        out += [f"LF:{f.lines_valid}", f"LH:{f.lines_covered}", "end_of_record"]
    return "\n".join(out) + "\n"


def coverage_files(coverage: SourceCoverage, main_dir: Path, cwd: Path, *, cobertura: Path | None = None,
                   lcov: Path | None = None) -> dict[Path, bytes | str]:
    """The files `equiv --cobertura/--lcov` writes, paths relative to report_base(main_dir, cwd). Raises
    ValueError when SOURCE_DATE_EPOCH is set but not an integer (only the Cobertura file carries a time)."""
    base = report_base(main_dir, cwd)
    paths = export_paths((f.path for f in coverage.files), main_dir, base)
    files: dict[Path, bytes | str] = {}
    if cobertura is not None:
        files[cobertura] = cobertura_xml(coverage, paths, base.as_posix())
    if lcov is not None:
        files[lcov] = lcov_text(coverage, paths)
    return files
