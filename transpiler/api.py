"""The public API of hh2iec: load a project, transpile it, simulate it, check its equivalence.

Every function returns a typed result and raises one exception type, `HH2IECError`
(`transpiler.diagnostics.CompileFailed`), whose `diagnostics` list every problem found (errors and
the warnings collected before them), each rendering as `file:line:col: error[CODE]: message`.
The `hh2iec` command line is a thin layer over these functions; see docs/api.md for a script that
runs the equivalence check over many OEM variants.
"""

from __future__ import annotations

import codecs
import dataclasses
from decimal import Decimal
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Callable, Iterable, Mapping

from transpiler.atomic import write_files_atomically
from transpiler.backends.report.iomap import IoMap
from transpiler.backends.report.report import io_map_of, user_pous
from transpiler.backends.st.backend import StResult
from transpiler.backends.transpile import transpile_program
from transpiler.diagnostics import NO_SPAN, CompileFailed, Diagnostic, Diagnostics, Span
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.mainfile import main_candidates
from transpiler.frontend.mpfile import mp_candidates, read_mp_file
from transpiler.frontend.pipeline import CompileResult, compile_project
from transpiler.frontend.preprocess import parse_define_value
from transpiler.ir import Program
from transpiler.language.semantics import Semantics, SemanticsError, make_semantics

if TYPE_CHECKING:   # the executors load only when a simulation or co-simulation runs, not for `check`
    from transpiler.verify.equiv import EquivalenceResult
    from transpiler.verify.mutate import MutationResult
    from transpiler.verify.scenario import Scenario
    from transpiler.verify.simulate import SimulationResult

HH2IECError = CompileFailed
DEFAULT_PROFILE = "itnc530"


def _usage(message: str, diags: Diagnostics | None = None) -> CompileFailed:
    items = list(diags.items) if diags is not None else []
    return CompileFailed(items + [Diagnostic.of("E-USAGE", NO_SPAN, message)])


# ---------------------------------------------------------------------------------------------
# loading


def semantics_for(profile: str | None = None, overrides: Mapping[str, object] | None = None,
                  scenario: Path | None = None) -> Semantics:
    """The control profile and semantic choices: `scenario`'s `profile`/`semantics` keys, overridden by `profile`
    and `overrides`; the default profile is itnc530. Raises HH2IECError on an unknown profile or setting."""
    from transpiler.verify.simulate import scenario_settings
    scenario_profile, settings, where = scenario_settings(scenario) if scenario is not None else (None, {}, None)
    merged = {str(k): v for k, v in settings.items()}
    merged.update({str(k): v for k, v in (overrides or {}).items()})
    try:
        return make_semantics(profile or scenario_profile or DEFAULT_PROFILE, merged)
    except SemanticsError as exc:
        if scenario is None:
            raise _usage(str(exc)) from None
        span = where or Span(str(scenario), 1, 1)
        raise CompileFailed([Diagnostic.of("E-SCENARIO", span, str(exc))]) from None


def project_options(main: Path, *, cfg: Path | None = None, defines: Mapping[str, str] | None = None,
                    include_dirs: Iterable[Path] = (), extra_defs: Iterable[Path] = (), encoding: str | None = None,
                    werror: bool = False) -> ProjectOptions:
    """Where the project is and how to configure it; DEFINE values are written as in OEM.cfg. `main` may be the
    project folder when exactly one .src file in it can be the main program. `encoding` forces one encoding for
    every file (default: detected per file); `werror` makes warnings fail the run. Raises HH2IECError (E-USAGE)
    when a named file or folder does not exist."""
    main = Path(main)
    if main.is_dir():
        candidates = main_candidates(main)
        if len(candidates) != 1:
            found = ", ".join(p.name for p in candidates) if candidates else "none"
            raise _usage(f"'{main}' is a folder; the main program is the .src file no other file USES and that "
                         f"exports nothing with GLOBAL; candidates: {found}. Name the main program instead")
        main = candidates[0]
    if not main.is_file():
        raise _usage(f"main program '{main}' does not exist")
    if encoding is not None:
        try:
            encoding = codecs.lookup(encoding).name
        except LookupError:
            raise _usage(f"unknown encoding '{encoding}' (e.g. utf-8, cp1252, latin-1)") from None
    if cfg is not None and not Path(cfg).is_file():
        raise _usage(f"configuration file '{cfg}' does not exist")
    include_dirs = tuple(Path(d) for d in include_dirs)
    for d in include_dirs:
        if not d.is_dir():
            raise _usage(f"-I folder '{d}' does not exist")
    values = {name.strip(): parse_define_value(str(value)) for name, value in (defines or {}).items()}
    return ProjectOptions(main=main, cfg=Path(cfg) if cfg is not None else None, defines=values,
                          include_dirs=include_dirs, extra_global_defs=tuple(Path(p) for p in extra_defs),
                          encoding=encoding, werror=werror)


@dataclasses.dataclass(frozen=True)
class Project:
    """A loaded project: the resolved program (the IR every later stage reads) and the warnings of loading."""

    options: ProjectOptions
    semantics: Semantics
    program: Program
    diagnostics: tuple[Diagnostic, ...]

    @property
    def main(self) -> Path:
        return self.options.main


def check_project(options: ProjectOptions, semantics: Semantics | None = None) -> CompileResult:
    """Preprocess, parse and resolve; never raises for bad input (the result carries every diagnostic)."""
    return compile_project(options, semantics or semantics_for())


def load_project(options: ProjectOptions, semantics: Semantics | None = None) -> Project:
    """Preprocess, parse and resolve the project; raises HH2IECError if anything is wrong with it."""
    semantics = semantics or semantics_for()
    result = compile_project(options, semantics)
    if not result.ok:
        raise CompileFailed(result.diagnostics.items)
    return Project(options, semantics, result.program, tuple(result.diagnostics.items))


# ---------------------------------------------------------------------------------------------
# transpiling


@dataclasses.dataclass(frozen=True)
class Transpilation:
    """The translated project: file name -> content, the ST text, and what the back end decided."""

    files: dict[str, bytes]
    st_text: str
    result: StResult
    mp_file: Path | None
    diagnostics: tuple[Diagnostic, ...]
    xml_validated: bool = False

    @property
    def io_map(self) -> IoMap:
        return io_map_of(self.result, self.mp_file.name if self.mp_file is not None else None)

    @property
    def pou_count(self) -> int:
        return len(user_pous(self.result))

    def write(self, out_dir: Path) -> None:
        """Write every file into `out_dir` all-or-nothing (OSError when the folder cannot be written); names with
        '/' go into sub-folders, which are created."""
        write_files_atomically({inside(Path(out_dir), name): data for name, data in self.files.items()})


def inside(out_dir: Path, name: str) -> Path:
    """Where the output file `name` ('/'-separated, relative) goes in `out_dir`. ValueError for a name that could
    leave the folder (absolute, '..', a backslash, empty): the back ends never make one, so it is a bug."""
    relative = PurePosixPath(name)
    if "\\" in name or relative.is_absolute() or any(part in ("", ".", "..") for part in name.split("/")):
        raise ValueError(f"output file name {name!r} does not name a file inside the output folder")
    return out_dir.joinpath(*relative.parts)


def machine_parameters_of(project: Project, mp_file: Path | None = None, *, allowed: Iterable[str] = ()
                          ) -> tuple[Path | None, dict[tuple[int, int], Decimal], Diagnostics]:
    """The machine parameters a translation is made with, chosen once: `mp_file`, else the one *.mp file beside
    the main program. Two or more candidates and no `mp_file` is an error (E-MP-AMBIGUOUS): the presets in the
    ST would depend on which file happened to be found. The returned collector allows the codes in `allowed`."""
    diags = Diagnostics(allowed=allowed)
    if mp_file is not None and not Path(mp_file).is_file():
        raise _usage(f"machine-parameter file '{mp_file}' does not exist")
    if mp_file is not None:
        path: Path | None = Path(mp_file)
    else:
        candidates = mp_candidates(project.main)
        if len(candidates) > 1:
            diags.report("E-MP-AMBIGUOUS", Span(str(project.main), 1, 1),
                         f"{len(candidates)} machine-parameter files beside the main program "
                         f"({', '.join(p.name for p in candidates)}): choose one with --mp")
        path = candidates[0] if len(candidates) == 1 else None
    values = read_mp_file(path, diags) if path is not None else {}
    return path, values, diags


def _fail_on_warnings(project: Project, diags: Diagnostics, what: str, runtime: Iterable = ()) -> None:
    """--werror: any warning (a diagnostic, or a runtime warning of the interpreter) becomes an E-WERROR error."""
    runtime = list(runtime)
    count = len(diags.warnings) + len(runtime)
    if project.options.werror and count and not diags.has_errors():
        diags.report("E-WERROR", NO_SPAN, f"{count} warning(s) {what} and --werror", *(w.render() for w in runtime))


def _load_scenarios(project: Project, paths: list[Path], names, diags: Diagnostics) -> list:
    """The scenario files bound to the project, their warnings collected as simulate shows them (the co-simulation
    builds its own stimulus later); raises on an error, or on a warning under --werror."""
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.stimulus import build_stimulus
    loaded = [load_scenario(path, names) for path in paths]
    for scenario in loaded:
        diags.extend(scenario.warnings)
        diags.extend(build_stimulus(scenario, names).diagnostics)
    _fail_on_warnings(project, diags, "of the scenarios")
    diags.raise_if_errors()
    return loaded


def _translate(project: Project, formats: set[str], mp_file: Path | None, allow_untranslated: bool,
               target: str = "matiec"):
    """Run the back ends with the project's machine parameters; raises on any error."""
    allowed = ("E-UNSUPPORTED",) if allow_untranslated else ()
    path, mp, diags = machine_parameters_of(project, mp_file, allowed=allowed)
    diags.raise_if_errors()
    out = transpile_program(project.program, diags, mp, formats, mp_file=path, target=target)
    if path is None and out.result.preset_vars:
        diags.report("E-MP-NONE", Span(str(project.main), 1, 1),
                     "no machine-parameter file (*.mp) beside the main program and no --mp: the timer and counter "
                     "presets of the translation are 0")
    _fail_on_warnings(project, diags, "of the translation")
    diags.raise_if_errors()    # a partial translation is never written or compared as if it were whole
    return path, mp, out, diags


def transpile(project: Project, *, formats: Iterable[str] = ("st", "xml"), mp_file: Path | None = None,
              validate_xml: bool = True, allow_untranslated: bool = False, target: str = "matiec") -> Transpilation:
    """Translate to ST / PLCopen XML (with the helper library hh_lib.st / hh_lib.xml, docs/hh_lib.md) plus
    report.md and io_map.csv. Raises HH2IECError on bad machine parameters, on code the back end cannot translate
    (E-UNSUPPORTED, unless `allow_untranslated`: then each is a warning and report.md opens with the list), or
    when an XML file does not validate against the cached TC6 schema (a bug in hh2iec). `target` (matiec, openplc,
    codesys, twincat) picks the dialect of project.st and project.xml (docs/import.md); for openplc the ST must also
    pass the runtime build's own rules (verify/openplc_rules.py, E-TARGET)."""
    formats = {f.strip().lower() for f in formats if f.strip()}
    if not formats or formats - {"st", "xml"}:
        raise _usage(f"formats are st, xml or both, not '{','.join(sorted(formats))}'")
    from transpiler.backends.st.dialect import TARGETS
    if target not in TARGETS:
        raise _usage(f"target is one of {', '.join(TARGETS)}, not '{target}'")
    path, _, out, diags = _translate(project, formats, mp_file, allow_untranslated, target)
    if target == "openplc":
        # The runtime's own build takes more than matiec does (names, accessor macros, I/O image): a translation it
        # would reject is a bug here, and nothing is written. The XML holds the same text.
        from transpiler.verify.openplc_rules import openplc_problems
        problems = openplc_problems(out.st_text, "project.st")
        if problems:
            raise CompileFailed(list(diags.items) + problems)
    validated = False
    if "xml" in formats and validate_xml:
        from transpiler.backends.plcopen.xsd import schema_path, validate_xml as validate
        if schema_path() is not None:
            # The project and its libraries; the files in subfolders are no TC6 XML of their own (the editor
            # project's plc.xml is project.xml byte for byte).
            for name in sorted(n for n in out.files if n.endswith(".xml") and "/" not in n):
                problems = validate(out.files[name], name)
                if problems:
                    raise CompileFailed(list(diags.items) + [Diagnostic.of(
                        "E-XSD", NO_SPAN, f"{name} does not validate against the TC6 schema (a bug in hh2iec; "
                        "nothing was written)", *problems)])
            validated = True
    return Transpilation(out.files, out.st_text, out.result, path, tuple(diags.items), validated)


# ---------------------------------------------------------------------------------------------
# simulating and co-simulating


@dataclasses.dataclass(frozen=True)
class Simulation:
    """One scenario run on the reference interpreter, with the scenario's own warnings."""

    scenario: Scenario
    run: SimulationResult
    diagnostics: tuple[Diagnostic, ...]


def simulate(project: Project, scenario: Path) -> Simulation:
    """Run the original program under a scenario file (expectations checked, trace kept)."""
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.stimulus import build_stimulus
    from transpiler.verify.simulate import project_names, run_scenario
    scenario = Path(scenario)
    if not scenario.is_file():
        raise _usage(f"scenario file '{scenario}' does not exist")
    names = project_names(project.program)
    diags = Diagnostics()
    loaded = load_scenario(scenario, names)
    diags.extend(loaded.warnings)
    stimulus = build_stimulus(loaded, names)
    diags.extend(stimulus.diagnostics)
    try:
        run = run_scenario(project.program, loaded, names, stimulus, diags=diags)
    except ShimUnavailable as exc:
        raise CompileFailed(list(diags.items) + [Diagnostic.of("E-TOOL", Span(str(scenario), 1, 1), str(exc))]) from None
    _fail_on_warnings(project, diags, "of the simulation", run.warnings)
    diags.raise_if_errors()
    return Simulation(loaded, run, tuple(diags.items))


@dataclasses.dataclass(frozen=True)
class Equivalence:
    """The equivalence check: every run's outcome, the verdict, and how the ST side was chosen."""

    result: EquivalenceResult
    st_name: str
    backend_note: str
    diagnostics: tuple[Diagnostic, ...]
    html_page: bytes | None = None          # the evidence as one HTML page, when asked for

    @property
    def equivalent(self) -> bool:
        return self.result.equivalent


def check_equivalence(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 0, seed: int = 1,
                      backend: str = "auto", st_file: Path | None = None, io_map_file: Path | None = None,
                      mp_file: Path | None = None, shrink: bool = True, vcd_dir: Path | None = None,
                      progress: Callable[[str, int, int], Callable[[int, int], None]] | None = None,
                      allow_untranslated: bool = False, html: bool = False) -> Equivalence:
    """Co-simulate the original program and its translation (or `st_file`) under each scenario and
    `random_cycles` of random stimulus, compared every cycle; divergent stimuli are shrunk. The ST runs exactly
    as written, with the presets of the machine parameters it was made with; a scenario whose own machine
    parameters give other presets ends its run with an error. With `allow_untranslated`, a translation that left
    code out is co-simulated but its verdict is at best NOT PROVEN. With `html` the result carries the evidence as
    one self-contained HTML page (each divergent run replayed once more with every cycle recorded)."""
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify import pipeline
    from transpiler.verify.equiv import choose_backend, run_equivalence
    from transpiler.verify.guided import generate
    from transpiler.verify.simulate import project_names
    scenarios = [Path(p) for p in scenarios]
    if not scenarios and random_cycles <= 0:
        raise _usage("equiv needs at least one --scenario or --random-cycles N")
    for path in scenarios:
        if not path.is_file():
            raise _usage(f"scenario file '{path}' does not exist")
    if st_file is not None and not Path(st_file).is_file():
        raise _usage(f"ST file '{st_file}' does not exist")
    mp_path, mp, transpiled, diags = _translate(project, {"st"}, mp_file, allow_untranslated)
    st_text, st_name = transpiled.st_text, "project.st"
    iomap = io_map_of(transpiled.result)
    if st_file is not None:
        st_file = Path(st_file)
        st_text, st_name = st_file.read_text(encoding="utf-8", errors="replace"), str(st_file)
        map_path = Path(io_map_file) if io_map_file is not None else st_file.parent / "io_map.csv"
        if map_path.is_file():
            try:
                iomap = IoMap.from_csv(map_path.read_text(encoding="utf-8"))
            except ValueError as exc:
                raise CompileFailed([Diagnostic.of("E-USAGE", Span(str(map_path), 1, 1), str(exc))]) from None
    chosen = choose_backend(backend, st_text, st_name, transpiled.result.project)
    if chosen.factory is None:
        raise CompileFailed(list(chosen.diagnostics) + [Diagnostic.of("E-TOOL", NO_SPAN, chosen.note)])
    names = project_names(project.program)
    loaded = _load_scenarios(project, scenarios, names, diags)
    if random_cycles > 0:
        # Coverage-guided corner stimulus, the user's scenarios its seeds (see verify/guided.py).
        loaded += generate(project.program, names, random_cycles, seed, loaded, machine_parameters=mp_path,
                           base_mp=mp)
    try:
        result = run_equivalence(project.program, chosen.factory, iomap, loaded, names, chosen.name,
                                 shrink_divergences=shrink, vcd_dir=vcd_dir, progress=progress, base_mp=mp,
                                 untranslated=tuple(transpiled.result.untranslated),
                                 pipelined=pipeline.worthwhile())
        page = None
        if html:
            from transpiler.verify.evidence import divergence_traces, equivalence_evidence
            from transpiler.verify.html_report import render_page
            traces = divergence_traces(result, project.program, chosen.factory, iomap, names, loaded, st_text, mp)
            page = render_page(equivalence_evidence(result, project.program, project.main.parent,
                                                    f"Equivalence of {project.main.name}", traces,
                                                    project.options.encoding))
    except ShimUnavailable as exc:
        raise CompileFailed([Diagnostic.of("E-TOOL", NO_SPAN, str(exc))]) from None
    return Equivalence(result, st_name, chosen.note, tuple(diags.items) + tuple(chosen.diagnostics), page)


@dataclasses.dataclass(frozen=True)
class Mutation:
    """The mutation analysis: every judged mutant, the score, and the ST text the mutants were made from."""

    result: "MutationResult"
    st_text: str
    backend_note: str
    diagnostics: tuple[Diagnostic, ...]


def mutation_page(project: Project, mutation: Mutation, min_score: float) -> bytes:
    """The mutation run as one self-contained HTML page: the score, and every surviving mutant beside the source line
    it was translated from."""
    from transpiler.verify.evidence import mutation_evidence
    from transpiler.verify.html_report import render_page
    return render_page(mutation_evidence(mutation.result, mutation.st_text, project.program, project.main.parent,
                                         f"Mutation check of {project.main.name}", min_score,
                                         project.options.encoding))


def _judged(judge, mutants: list, jobs: int, progress: Callable[[int, int], None] | None) -> list:
    """The verdicts of `mutants` (see verify/mutate.py judge_all); raises CompileFailed when the unmutated
    translation does not agree with the reference under the stimulus."""
    from transpiler.verify.mutate import judge_all, prepare
    judging = prepare(judge, mutants, jobs)
    if judging.problems:
        raise _usage("the unmutated translation is not equivalent under the stimulus, mutation results "
                     "would mean nothing (run hh2iec equiv): " + "; ".join(judging.problems[:5]))
    verdicts = []
    for verdict in judge_all(judge, mutants, jobs, judging):
        verdicts.append(verdict)
        if progress is not None:
            progress(len(verdicts), len(mutants))
    return verdicts


def mutate(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 2000, seed: int = 1,
           backend: str = "auto", mp_file: Path | None = None, jobs: int = 1, count: int = 0,
           equivalent_file: Path | None = None, mutants_file: Path | None = None,
           progress: Callable[[int, int], None] | None = None) -> Mutation:
    """Mutants of the emitted ST judged by co-simulation under the scenarios and `random_cycles` of
    coverage-guided stimulus (see verify/mutate.py); `count` > 0 judges a seeded sample spread over the
    operators, `mutants_file` (the --survivors format) only the mutants it lists; `equivalent_file` lists mutants
    judged equivalent, which leave the denominator. Raises CompileFailed on bad input, or when the unmutated
    translation is not equivalent under the stimulus."""
    import os
    import tempfile
    import time
    from transpiler.backends.st.check import find_iec2c
    from transpiler.verify.cosim import BuiltinSchema, builtin_side_factory
    from transpiler.verify.equiv import choose_backend
    from transpiler.verify.guided import generate
    from transpiler.verify.mutate import (Judge, MutationResult, apply_equivalents, choose, load_equivalents,
                                          mutation_sites)
    from transpiler.verify.simulate import project_names
    from transpiler.exec.interp import compile_program
    scenarios = [Path(p) for p in scenarios]
    if not scenarios and random_cycles <= 0:
        raise _usage("mutate needs at least one --scenario or --random-cycles N")
    for path in [*scenarios, *(Path(f) for f in (equivalent_file, mutants_file) if f)]:
        if not path.is_file():
            raise _usage(f"file '{path}' does not exist")
    equivalents = load_equivalents(Path(equivalent_file)) if equivalent_file else []
    listed = {e.key for e in load_equivalents(Path(mutants_file))} if mutants_file else None
    mp_path, mp, transpiled, diags = _translate(project, {"st"}, mp_file, False)
    st_text, iec = transpiled.st_text, transpiled.result.project
    chosen = choose_backend(backend, st_text, "project.st", iec)
    if chosen.factory is None:
        raise CompileFailed(list(chosen.diagnostics) + [Diagnostic.of("E-TOOL", NO_SPAN, chosen.note)])
    if chosen.name == "matiec":
        from transpiler.exec.compiled.matiec_side import matiec_side_factory
        iec2c = find_iec2c()
        side_factory = lambda text: matiec_side_factory(text, iec, iec2c)  # noqa: E731
        schema_factory = None
    else:
        side_factory = lambda text: builtin_side_factory(text, "project.st")  # noqa: E731
        schema_factory = lambda text, mutations: BuiltinSchema(text, mutations, "project.st")  # noqa: E731
    names = project_names(project.program)
    loaded = _load_scenarios(project, scenarios, names, diags)
    users = list(loaded)                    # the user's scenarios, before the generated ones join them
    loaded += generate(project.program, names, random_cycles, seed, loaded, machine_parameters=mp_path, base_mp=mp)
    judge = Judge(project.program, io_map_of(transpiled.result), names, sorted(loaded, key=lambda s: s.cycles),
                  st_text, side_factory, compile_program(project.program), mp, schema_factory)
    saved_cache = os.environ.get("HH2IEC_CACHE")
    with tempfile.TemporaryDirectory(prefix="hh2iec-mutants-") as cache:
        # Mutant libraries are throw-away: they stay out of the user's build cache.
        os.environ["HH2IEC_CACHE"] = cache
        try:
            sites = mutation_sites(st_text)
            mutants = choose(sites, count, seed)
            if listed is not None:
                mutants = [m for m in mutants if m.key in listed]
            start = time.perf_counter()
            verdicts = _judged(judge, mutants, jobs, progress)
            seconds = time.perf_counter() - start
        finally:
            if saved_cache is None:
                os.environ.pop("HH2IEC_CACHE", None)
            else:
                os.environ["HH2IEC_CACHE"] = saved_cache
    verdicts.sort(key=lambda v: (v.mutant.line, v.mutant.operator, v.mutant.description))
    verdicts, unmatched = apply_equivalents(verdicts, equivalents, sites)
    absent = len(listed - {m.key for m in sites}) if listed is not None else 0
    files = {id(s): str(s.source) for s in users if s.source is not None}
    result = MutationResult(verdicts, len(sites), [s.name for s in judge.scenarios], chosen.name, seconds, unmatched,
                            listed_absent=absent, scenario_files=tuple(files.get(id(s), "") for s in judge.scenarios),
                            pou_sources={p.name: p.source_map for p in iec.pous if p.source_map})
    return Mutation(result, st_text, chosen.note, tuple(diags.items) + tuple(chosen.diagnostics))
