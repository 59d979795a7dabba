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

from transpiler.diagnostics import NO_SPAN, CompileFailed, Diagnostic, Diagnostics, Span
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.mainfile import main_candidates
from transpiler.frontend.mpfile import mp_candidates, read_mp_file
from transpiler.frontend.pipeline import CompileResult, compile_project
from transpiler.frontend.preprocess import parse_define_value
from transpiler.ir import Program
from transpiler.language.semantics import Semantics, SemanticsError, make_semantics

if TYPE_CHECKING:   # the back ends, executors and shard planning load only when a translation or simulation runs, not for `check`
    from transpiler.backends.report.iomap import IoMap
    from transpiler.backends.st.backend import StResult
    from transpiler.verify.shard import ShardSpec
    from transpiler.verify.screens import Screen, ScreenRequest
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
    scenario_profile, settings, where = None, {}, None
    if scenario is not None:
        from transpiler.verify.simulate import scenario_settings
        scenario_profile, settings, where = scenario_settings(scenario)
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
                    werror: bool = False, mp_data: Path | None = None, mp_config: Path | None = None
                    ) -> ProjectOptions:
    """Where the project is and how to configure it; DEFINE values are written as in OEM.cfg. `main` may be the
    project folder when exactly one .src file in it can be the main program. `encoding` forces one encoding for
    every file (default: detected per file); `werror` makes warnings fail the run. `mp_data` / `mp_config` name
    the PLC data tables (default: MP_Data.tab / MP_Config.tab in the folder MP beside the main program, or beside
    it). Raises HH2IECError (E-USAGE) when a named file or folder does not exist."""
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
    tables = {}
    for name, flag, path in (("MP_Data.tab", "--mp-data", mp_data), ("MP_Config.tab", "--mp-config", mp_config)):
        if path is not None:
            if not Path(path).is_file():
                raise _usage(f"{flag} file '{path}' does not exist")
            tables[name] = Path(path)
    values = {name.strip(): parse_define_value(str(value)) for name, value in (defines or {}).items()}
    return ProjectOptions(main=main, cfg=Path(cfg) if cfg is not None else None, defines=values,
                          include_dirs=include_dirs, extra_global_defs=tuple(Path(p) for p in extra_defs),
                          encoding=encoding, werror=werror, data_tables=tables)


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
        from transpiler.backends.report.report import io_map_of
        return io_map_of(self.result, self.mp_file.name if self.mp_file is not None else None)

    @property
    def pou_count(self) -> int:
        from transpiler.backends.report.report import user_pous
        return len(user_pous(self.result))

    def write(self, out_dir: Path) -> None:
        """Write every file into `out_dir` all-or-nothing (OSError when the folder cannot be written); names with
        '/' go into sub-folders, which are created."""
        from transpiler.atomic import write_files_atomically     # (only a command that writes needs it)
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
               target: str = "matiec", xml_made=None):
    """Run the back ends with the project's machine parameters (`xml_made`: see transpile_program); raises on any
    error."""
    allowed = ("E-UNSUPPORTED",) if allow_untranslated else ()
    path, mp, diags = machine_parameters_of(project, mp_file, allowed=allowed)
    diags.raise_if_errors()
    from transpiler.backends.transpile import transpile_program
    out = transpile_program(project.program, diags, mp, formats, mp_file=path, target=target, xml_made=xml_made)
    if path is None and out.result.preset_vars:
        diags.report("E-MP-NONE", Span(str(project.main), 1, 1),
                     "no machine-parameter file (*.mp) beside the main program and no --mp: the timer and counter "
                     "presets of the translation are 0")
    _fail_on_warnings(project, diags, "of the translation")
    diags.raise_if_errors()    # a partial translation is never written or compared as if it were whole
    return path, mp, out, diags


def _xml_validation():
    """A BackgroundValidation against the cached TC6 schema (read once for all the files), None when it is not
    cached."""
    from transpiler.backends.plcopen.xsd import BackgroundValidation, load_schema, schema_path
    return BackgroundValidation(load_schema()) if schema_path() is not None else None


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
    validation = _xml_validation() if "xml" in formats and validate_xml else None
    try:
        path, _, out, diags = _translate(project, formats, mp_file, allow_untranslated, target,
                                         validation.start if validation is not None else None)
    finally:
        if validation is not None:
            validation.close()
    if target == "openplc":
        # The runtime's own build takes more than matiec does (names, accessor macros, I/O image): a translation it
        # would reject is a bug here, and nothing is written. The XML holds the same text.
        from transpiler.verify.openplc_rules import openplc_problems
        problems = openplc_problems(out.st_text, "project.st")
        if problems:
            raise CompileFailed(list(diags.items) + problems)
    validated = False
    if validation is not None:
        # The project and its libraries; the files in subfolders are no TC6 XML of their own (the editor
        # project's plc.xml is project.xml byte for byte).
        for name in sorted(n for n in out.files if n.endswith(".xml") and "/" not in n):
            problems = validation.problems(name, out.files[name])
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
    screens: tuple[Screen, ...] = ()       # the masks asked for with `show_masks`, drawn from the interpreter


def screen_requests(project: Project, show_masks: Iterable[str]) -> list[ScreenRequest]:
    """The `NAME@CYCLE` texts as requests for the project's masks; raises HH2IECError (E-USAGE) on a name that is no
    mask of the project or a text without a cycle."""
    from transpiler.verify.screens import parse_requests
    requests, problems = parse_requests(project.program.masks, show_masks)
    if problems:
        raise CompileFailed([Diagnostic.of("E-USAGE", NO_SPAN, p) for p in problems])
    return requests


def simulate(project: Project, scenario: Path, show_masks: Iterable[str] = ()) -> Simulation:
    """Run the original program under a scenario file (expectations checked, trace kept). `show_masks` (`NAME@CYCLE`,
    docs/masks.md) draws those masks from the interpreter's operands after those cycles."""
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.stimulus import build_stimulus
    from transpiler.verify.simulate import project_names, run_scenario
    scenario = Path(scenario)
    if not scenario.is_file():
        raise _usage(f"scenario file '{scenario}' does not exist")
    from transpiler.verify.screens import Screen, render_mask
    requests = screen_requests(project, show_masks)
    names = project_names(project.program)
    diags = Diagnostics()
    loaded = load_scenario(scenario, names)
    diags.extend(loaded.warnings)
    stimulus = build_stimulus(loaded, names)
    diags.extend(stimulus.diagnostics)
    drawn: dict[int, tuple[str, ...]] = {}

    def draw(cycle: int, machine) -> None:
        for i, request in enumerate(requests):
            if request.cycle == cycle:
                drawn[i] = render_mask(request.mask, machine.read, project.program)
    try:
        run = run_scenario(project.program, loaded, names, stimulus, diags=diags,
                           after_cycle=draw if requests else None)
    except ShimUnavailable as exc:
        raise CompileFailed(list(diags.items) + [Diagnostic.of("E-TOOL", Span(str(scenario), 1, 1), str(exc))]) from None
    _fail_on_warnings(project, diags, "of the simulation", run.warnings)
    diags.raise_if_errors()
    screens = tuple(Screen(loaded.name or scenario.stem, r.mask.name, r.cycle, drawn.get(i),
                           note="" if i in drawn else f"the run ended after {run.cycles_run} cycles")
                    for i, r in enumerate(requests))
    return Simulation(loaded, run, tuple(diags.items), screens)


@dataclasses.dataclass(frozen=True)
class Plan:
    """The units of a check (equiv's runs, mutate's mutants) in plan order, each with a cost estimate (cycles to
    co-simulate), and the digest of the inputs they follow from. Every shard of a check computes the same plan; a
    unit's number (1-based) is its place in it. `generated` holds the runs the coverage-guided search chose (written
    into a plan file, so that shards need not search again)."""

    command: str
    digest: str
    names: tuple[str, ...]
    costs: tuple[float, ...]
    generated: tuple = ()
    setup_seconds: float = 0.0              # what translating and loading the scenarios took in this process
    search_seconds: float = 0.0             # what the coverage-guided search took (0 with a plan file)
    # mutate: per run (named, in the order mutants go through them) the numbers of the mutants its run of the
    # unmutated translation infects, from probing every run once; a plan file carries it so shards need not probe
    infected: tuple[tuple[str, tuple[int, ...]], ...] = ()

    def assignment(self, count: int) -> list[int]:
        """The shard (1..count) of each unit (shard.partition over the costs)."""
        from transpiler.verify.shard import partition
        return partition(self.costs, count)

    def selected(self, share: "Share") -> list[int]:
        """The numbers of the units `share` runs. Raises HH2IECError (E-USAGE) for a number outside the plan."""
        count = len(self.names)
        if share.sample > 0:
            return sorted({1 + i * count // share.sample for i in range(min(share.sample, count))})
        if share.only is not None:
            if not 1 <= share.only <= count:
                raise _usage(f"--only {share.only}: the plan has units 1 to {count}")
            return [share.only]
        if share.shard is None:
            return list(range(1, count + 1))
        return [i + 1 for i, k in enumerate(self.assignment(share.shard.count)) if k == share.shard.index]


@dataclasses.dataclass(frozen=True)
class Share:
    """Which units of a check's plan this process runs and where its generated runs come from: the units of `shard`
    (K of N), the one numbered `only`, or `sample` units spread evenly (to estimate the time of one); `plan_file`
    holds the runs the coverage-guided search chose once for every shard. The default: every unit, searched here."""

    shard: "ShardSpec | None" = None
    only: int | None = None
    plan_file: Path | None = None
    sample: int = 0


EVERYTHING = Share()


def _inputs_digest(command: str, project: Project, mp_path: Path | None, files: Iterable[tuple[str, Path | None]],
                   settings: Mapping[str, object]) -> str:
    """The digest of everything a check's result follows from (see verify/shard.inputs_digest): the project's
    files, the machine parameters, the named input files, the semantics, defines and the settings given."""
    from transpiler import __version__
    from transpiler.verify.shard import inputs_digest
    folder = project.main.parent
    sources = [("source", folder / name) for name in project.program.source_files]
    options = project.options
    semantics = project.semantics
    all_settings = {"profile": semantics.profile.name, "semantics": dict(semantics.values),
                    "defines": {k: str(v) for k, v in options.defines.items()}, "encoding": options.encoding,
                    "werror": options.werror, **settings}
    return inputs_digest(command, __version__, [*sources, ("machine parameters", mp_path), *files], all_settings)


def _generated_runs(project: Project, names, seeds: list, mp_path: Path | None, mp: Mapping | None,
                    random_cycles: int, seed: int, plan: "PlanFile | None") -> tuple[list, float]:
    """The runs of the coverage-guided search (verify/guided.py; the user's scenarios its seeds) and the seconds it
    took; with a plan file, the runs it chose when the plan was made, read back instead of searching again."""
    import time
    from transpiler.verify.guided import generate
    if plan is not None:
        return [plan.generated_run(i, names) for i in range(len(plan.generated))], 0.0
    start = time.perf_counter()
    runs = generate(project.program, names, random_cycles, seed, seeds, machine_parameters=mp_path, base_mp=mp)
    return runs, time.perf_counter() - start


def _shard_problem(message: str, at: Path | None = None) -> CompileFailed:
    return CompileFailed([Diagnostic.of("E-SHARD", Span(str(at), 1, 1) if at is not None else NO_SPAN, message)])


@dataclasses.dataclass(frozen=True)
class PlanFile:
    """A plan file written by `--plan N --plan-file FILE`, read once and checked (PlanFile.read): its units (name
    and cost of each), the generated runs as scenario texts and, for mutate, the infection map."""

    path: Path
    units: tuple[dict, ...]
    generated: tuple[str, ...]
    infected: object = None                 # as written: checked against the runs by PlanFile.infection

    @classmethod
    def read(cls, path: Path, command: str, digest: str) -> "PlanFile":
        """Raises HH2IECError (E-SHARD) when the file is not a plan of `command`, was made from other inputs than
        those of `digest`, or its units or generated runs are damaged."""
        import json
        from transpiler.verify.shard import FORMAT
        path = Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise _shard_problem(f"cannot read the plan file: {exc}", path) from None
        if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("kind") != "hh2iec-plan":
            raise _shard_problem("not a plan file of this hh2iec (write one with --plan N --plan-file FILE)", path)
        if data.get("command") != command:
            raise _shard_problem(f"a plan file of `{data.get('command')}`, not of `{command}`", path)
        if data.get("digest") != digest:
            raise _shard_problem("the plan file was made from other inputs (sources, scenarios, settings or hh2iec "
                                 "version) than this run's: make it again with the same arguments", path)
        units, generated = data.get("units", []), data.get("generated", [])
        if (not isinstance(units, list) or not isinstance(generated, list)
                or not all(isinstance(t, str) for t in generated)):
            raise _shard_problem("the plan file's units or generated runs are damaged: make it again", path)
        for number, unit in enumerate(units, 1):
            if (not isinstance(unit, dict) or unit.get("unit") != number or not isinstance(unit.get("name"), str)
                    or not isinstance(unit.get("cost"), (int, float)) or isinstance(unit.get("cost"), bool)):
                raise _shard_problem(f"the plan file's unit {number} is damaged: make it again", path)
        return cls(path, tuple(units), tuple(generated), data.get("infected"))

    def generated_run(self, index: int, names):
        """Generated run `index` (0-based), as a scenario."""
        from transpiler.verify.scenario import ScenarioError, scenario_from_text
        try:
            return scenario_from_text(self.generated[index], f"{self.path}#generated{index + 1}", Path.cwd(), names)
        except ScenarioError as exc:
            raise CompileFailed(list(exc.diagnostics)) from None

    def infection(self, scenarios: list) -> tuple[frozenset[int], ...] | None:
        """The infection map per run in judging order (plan numbers of the mutants), or None when the plan has none
        (a backend without schemata); E-SHARD when it does not fit these runs and units."""
        entries = self.infected
        if entries is None:
            return None
        count = len(self.units)
        if (not isinstance(entries, list) or len(entries) != len(scenarios)
                or any(not isinstance(e, dict) or e.get("run") != s.name or not isinstance(e.get("mutants"), list)
                       or not all(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= count
                                  for n in e["mutants"]) for e, s in zip(entries, scenarios))):
            raise _shard_problem("the plan file's infection map does not fit its runs and mutants: make it again",
                                 self.path)
        return tuple(frozenset(e["mutants"]) for e in entries)


def plan_file_text(plan: Plan) -> str:
    """The plan file (`--plan N --plan-file FILE`): the inputs' digest and the generated runs as scenario YAML
    (machine-parameter files relative to the current folder, where every shard runs)."""
    import json
    from transpiler.verify.shard import FORMAT
    from transpiler.verify.stimulus import scenario_to_yaml
    return json.dumps({"kind": "hh2iec-plan", "format": FORMAT, "command": plan.command, "digest": plan.digest,
                       "units": [{"unit": i + 1, "name": n, "cost": c} for i, (n, c) in
                                 enumerate(zip(plan.names, plan.costs))],
                       "generated": [scenario_to_yaml(s, Path.cwd()) for s in plan.generated],
                       **({"infected": [{"run": name, "mutants": list(numbers)} for name, numbers in plan.infected]}
                          if plan.infected else {})}, indent=1) + "\n"


@dataclasses.dataclass(frozen=True)
class Equivalence:
    """The equivalence check: every run's outcome, the verdict, and how the ST side was chosen."""

    result: EquivalenceResult
    st_name: str
    backend_note: str
    diagnostics: tuple[Diagnostic, ...]
    html_page: bytes | None = None          # the evidence as one HTML page, when asked for
    screens: tuple[Screen, ...] = ()        # the masks asked for, drawn from both sides of each scenario's run
    plan: "Plan | None" = None              # every run of the check, of which `result` holds the selected ones

    @property
    def screens_differ(self) -> bool:
        return any(s.differs for s in self.screens)

    @property
    def equivalent(self) -> bool:
        return self.result.equivalent


@dataclasses.dataclass
class _EquivSetup:
    """What an equivalence check sets up before it runs anything: the translation, the executor and the runs."""

    st_text: str
    st_name: str
    iomap: IoMap
    chosen: object
    names: object
    mp: dict | None                 # the machine parameters the translation was made with; None: the project has none
    runs: list
    plan: Plan
    diagnostics: Diagnostics
    untranslated: tuple


def _equivalence_setup(project: Project, scenarios: list[Path], random_cycles: int, seed: int, backend: str,
                       st_file: Path | None, io_map_file: Path | None, mp_file: Path | None, shrink: bool,
                       allow_untranslated: bool, plan_file: Path | None,
                       share: "Share | None" = None) -> _EquivSetup:
    """The translation, its executor and the runs of the check. With a plan file and a `share`, `runs` holds only
    the runs the share makes (None in the other places): their units and costs come from the plan file."""
    import time
    from transpiler.verify.equiv import choose_backend
    from transpiler.verify.simulate import project_names
    start = time.perf_counter()
    if not scenarios and random_cycles <= 0:
        raise _usage("equiv needs at least one --scenario or --random-cycles N")
    for path in scenarios:
        if not path.is_file():
            raise _usage(f"scenario file '{path}' does not exist")
    if st_file is not None and not Path(st_file).is_file():
        raise _usage(f"ST file '{st_file}' does not exist")
    mp_path, mp, transpiled, diags = _translate(project, {"st"}, mp_file, allow_untranslated)
    st_text, st_name = transpiled.st_text, "project.st"
    from transpiler.backends.report.iomap import IoMap
    from transpiler.backends.report.report import io_map_of
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
    digest = _equivalence_digest(project, mp_path, scenarios, random_cycles, seed, backend, st_file, io_map_file,
                                 shrink, allow_untranslated)
    chosen = choose_backend(backend, st_text, st_name, transpiled.result.project)
    if chosen.factory is None:
        raise CompileFailed(list(chosen.diagnostics) + [Diagnostic.of("E-TOOL", NO_SPAN, chosen.note)])
    names = project_names(project.program)
    base_mp = mp if mp_path is not None else None      # None: the project has no machine data of its own
    planned = PlanFile.read(plan_file, "equiv", digest) if plan_file is not None else None
    if planned is not None and share is not None:
        runs, plan = _runs_of_plan_file(project, planned, digest, names, scenarios, share, diags)
        plan = dataclasses.replace(plan, setup_seconds=time.perf_counter() - start)
    else:
        loaded = _load_scenarios(project, scenarios, names, diags)
        setup_seconds = time.perf_counter() - start
        generated, search_seconds = _generated_runs(project, names, loaded, mp_path, base_mp, random_cycles, seed,
                                                    planned)
        runs = loaded + generated
        plan = Plan("equiv", digest, tuple(s.name for s in runs), tuple(float(s.cycles) for s in runs),
                    tuple(generated), setup_seconds, search_seconds)
    return _EquivSetup(st_text, st_name, iomap, chosen, names, base_mp, runs, plan, diags,
                       tuple(transpiled.result.untranslated))


def _runs_of_plan_file(project: Project, planned: PlanFile, digest: str, names, scenarios: list[Path],
                       share: "Share", diags: Diagnostics) -> tuple[list, Plan]:
    """The plan of a plan file and the runs `share` makes, in plan order (None for the others). Only those
    scenario files and generated runs are loaded: the job that wrote the plan loaded and checked every one of the
    same inputs (the digest says so), and a shard need not parse the runs of the other shards again."""
    units, path = planned.units, planned.path
    if len(units) != len(scenarios) + len(planned.generated):
        raise _shard_problem("the plan file's units are not its scenarios and generated runs: make it again", path)
    plan = Plan("equiv", digest, tuple(u["name"] for u in units), tuple(float(u["cost"]) for u in units))
    wanted = plan.selected(share)
    runs: list = [None] * len(units)
    from_files = [number for number in wanted if number <= len(scenarios)]
    for number, run in zip(from_files, _load_scenarios(project, [scenarios[n - 1] for n in from_files], names,
                                                       diags)):
        runs[number - 1] = run
    for number in wanted:
        if number > len(scenarios):
            runs[number - 1] = planned.generated_run(number - 1 - len(scenarios), names)
    for number in wanted:
        if runs[number - 1].name != plan.names[number - 1] or float(runs[number - 1].cycles) != plan.costs[number - 1]:
            raise _shard_problem(f"run {number} of the plan file is not the run these inputs give: make it again",
                                 path)
    return runs, plan


def _equivalence_digest(project: Project, mp_path: Path | None, scenarios: list[Path], random_cycles: int, seed: int,
                        backend: str, st_file: Path | None, io_map_file: Path | None, shrink: bool,
                        allow_untranslated: bool) -> str:
    map_path = None
    if st_file is not None:
        map_path = Path(io_map_file) if io_map_file is not None else Path(st_file).parent / "io_map.csv"
        map_path = map_path if map_path.is_file() else None
    return _inputs_digest("equiv", project, mp_path,
                          [*(("scenario", path) for path in scenarios), ("st", st_file), ("io map", map_path)],
                          {"random_cycles": random_cycles, "seed": seed, "backend": backend, "shrink": shrink,
                           "allow_untranslated": allow_untranslated})


def equivalence_digest(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 0, seed: int = 1,
                       backend: str = "auto", st_file: Path | None = None, io_map_file: Path | None = None,
                       mp_file: Path | None = None, shrink: bool = True, allow_untranslated: bool = False) -> str:
    """The inputs' digest check_equivalence gives its plan with the same arguments, without running anything (the
    merge of shard results checks that the sources it loads are the ones the shards ran on)."""
    mp_path, _, diags = machine_parameters_of(project, mp_file)
    diags.raise_if_errors()
    return _equivalence_digest(project, mp_path, [Path(p) for p in scenarios], random_cycles, seed, backend,
                               st_file, io_map_file, shrink, allow_untranslated)


def plan_equivalence(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 0, seed: int = 1,
                     backend: str = "auto", st_file: Path | None = None, io_map_file: Path | None = None,
                     mp_file: Path | None = None, shrink: bool = True, allow_untranslated: bool = False,
                     plan_file: Path | None = None) -> tuple[Plan, float]:
    """The runs check_equivalence would make with the same arguments (the coverage-guided search included), and
    the seconds per co-simulated cycle measured on one run of about the mean length (the calibration run)."""
    import time
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify.equiv import run_equivalence
    setup = _equivalence_setup(project, [Path(p) for p in scenarios], random_cycles, seed, backend, st_file,
                               io_map_file, mp_file, shrink, allow_untranslated, plan_file)
    costs = setup.plan.costs
    mean = sum(costs) / len(costs)
    probe = min(range(len(costs)), key=lambda i: (abs(costs[i] - mean), i))
    start = time.perf_counter()
    try:
        run_equivalence(project.program, setup.chosen.factory, setup.iomap, [setup.runs[probe]], setup.names,
                        setup.chosen.name, shrink_divergences=False, base_mp=setup.mp)
    except ShimUnavailable as exc:
        raise CompileFailed([Diagnostic.of("E-TOOL", NO_SPAN, str(exc))]) from None
    return setup.plan, (time.perf_counter() - start) / max(1.0, costs[probe])


def check_equivalence(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 0, seed: int = 1,
                      backend: str = "auto", st_file: Path | None = None, io_map_file: Path | None = None,
                      mp_file: Path | None = None, shrink: bool = True, vcd_dir: Path | None = None,
                      progress: Callable[[str, int, int], Callable[[int, int], None]] | None = None,
                      allow_untranslated: bool = False, html: bool = False, show_masks: Iterable[str] = (),
                      share: Share = EVERYTHING) -> Equivalence:
    """Co-simulate the original program and its translation (or `st_file`) under each scenario and
    `random_cycles` of random stimulus, compared every cycle; divergent stimuli are shrunk. The ST's shipped
    machine-parameter values must be the project's (else E-MP-TRANSLATION); a scenario's own machine parameters
    are written into its globals as run-time data (values it cannot hold: E-MP-UNREPRESENTABLE, NO VERDICT). With
    `allow_untranslated`, a translation that left code out is co-simulated but its verdict is at best NOT PROVEN.
    With `html` the result carries the evidence as one self-contained HTML page (each divergent run replayed once more with every cycle recorded). `show_masks`
    (`NAME@CYCLE`) replays each scenario once more and draws those masks from both sides after those cycles
    (Equivalence.screens; a pair of screens that differ is a finding of its own, `screens_differ`). `share` picks
    the runs of the plan to make (a shard's, one alone) and where the generated ones come from."""
    from transpiler.exec.compiled.shim import ShimUnavailable
    from transpiler.verify import pipeline
    from transpiler.verify.equiv import run_equivalence
    scenarios = [Path(p) for p in scenarios]
    requests = screen_requests(project, show_masks)
    if requests and not scenarios:
        raise _usage("--show-mask draws masks in the runs of --scenario files: give at least one")
    setup = _equivalence_setup(project, scenarios, random_cycles, seed, backend, st_file, io_map_file, mp_file,
                               shrink, allow_untranslated, share.plan_file, None if requests else share)
    chosen, names, iomap, mp = setup.chosen, setup.names, setup.iomap, setup.mp
    selected = setup.plan.selected(share)
    loaded = [setup.runs[i - 1] for i in selected]
    user_scenarios = setup.runs[:len(scenarios)]        # the plan lists the user's scenarios first
    try:
        result = run_equivalence(project.program, chosen.factory, iomap, loaded, names, chosen.name,
                                 shrink_divergences=shrink, vcd_dir=vcd_dir, progress=progress, base_mp=mp,
                                 untranslated=setup.untranslated,
                                 pipelined=pipeline.worthwhile(), explain_missing=share.shard is None)
        result.run_ids = tuple(selected)
        page = None
        if html:
            from transpiler.verify.evidence import divergence_traces, equivalence_evidence
            from transpiler.verify.html_report import render_page
            traces = divergence_traces(result, project.program, chosen.factory, iomap, names, loaded, setup.st_text,
                                       mp)
            page = render_page(equivalence_evidence(result, project.program, project.main.parent,
                                                    f"Equivalence of {project.main.name}", traces,
                                                    project.options.encoding))
        screens: tuple = ()
        if requests:
            from transpiler.verify.screens import draw_both_sides
            screens = draw_both_sides(project.program, chosen.factory, iomap, user_scenarios, names, requests, mp)
    except ShimUnavailable as exc:
        raise CompileFailed([Diagnostic.of("E-TOOL", NO_SPAN, str(exc))]) from None
    return Equivalence(result, setup.st_name, chosen.note, tuple(setup.diagnostics.items) + tuple(chosen.diagnostics),
                       page, screens, setup.plan)


@dataclasses.dataclass(frozen=True)
class Mutation:
    """The mutation analysis: every judged mutant, the score, and the ST text the mutants were made from."""

    result: "MutationResult"
    st_text: str
    backend_note: str
    diagnostics: tuple[Diagnostic, ...]
    plan: Plan | None = None                # every mutant of the check, of which `result` holds the judged ones
    unit_ids: Mapping = dataclasses.field(default_factory=dict)     # judged mutant -> its number in the plan


def mutation_page(project: Project, mutation: Mutation, min_score: float) -> bytes:
    """The mutation run as one self-contained HTML page: the score, and every surviving mutant beside the source line
    it was translated from."""
    from transpiler.verify.evidence import mutation_evidence
    from transpiler.verify.html_report import render_page
    return render_page(mutation_evidence(mutation.result, mutation.st_text, project.program, project.main.parent,
                                         f"Mutation check of {project.main.name}", min_score,
                                         project.options.encoding))


def _mutation_runs(project: Project, names, seeds: list, mp_path: Path | None, mp: Mapping | None,
                   scenarios: list[Path],
                   equivalent_file: Path | None, mutants_file: Path | None, settings: tuple[int, int, str, int],
                   share: Share) -> tuple[str, list, float, PlanFile | None]:
    """The inputs' digest of a mutation check (`settings`: random cycles, seed, backend choice and count), its
    generated runs with the seconds their search took, and the plan file they were read from (if any)."""
    random_cycles, seed, backend, count = settings
    digest = _inputs_digest("mutate", project, mp_path, [*(("scenario", path) for path in scenarios),
                                                         ("equivalent", equivalent_file), ("mutants", mutants_file)],
                            {"random_cycles": random_cycles, "seed": seed, "backend": backend, "count": count})
    planned = PlanFile.read(share.plan_file, "mutate", digest) if share.plan_file is not None else None
    return (digest, *_generated_runs(project, names, seeds, mp_path, mp, random_cycles, seed, planned), planned)


def _mutation_plan(digest: str, mutants: list, scenarios: list, generated: list, search_seconds: float,
                   share: Share) -> tuple[Plan, dict]:
    """The mutants in plan order, and the ones `share` judges with their numbers. A mutant's cost estimate is the
    cycles of every scenario, what it takes to survive (a kill stops early, at a place no estimate made before
    judging knows). The set-up time is the caller's to measure."""
    plan = Plan("mutate", digest, tuple(f"{m.pou}: {m.operator}: {m.description}" for m in mutants),
                (float(sum(s.cycles for s in scenarios)),) * len(mutants), tuple(generated), 0.0, search_seconds)
    return plan, {mutants[i - 1]: i for i in plan.selected(share)}


def _judge_share(judge, plan: Plan, mutants: list, unit_ids: dict, share: Share, planned: PlanFile | None,
                 jobs: int, progress: Callable[[int, int], None] | None) -> tuple[Plan, list]:
    """The verdicts of the mutants `share` judges (`unit_ids`: each with its plan number). Making a plan (a sample
    share) probes with every mutant of the plan and keeps the infection map in it; a shard given a plan file with a
    map uses it instead of probing every run again."""
    if share.sample > 0:
        indexes = [unit_ids[m] - 1 for m in unit_ids]
        verdicts, infected = _judged(judge, mutants, jobs, progress, indexes=indexes)
        if infected is not None:
            plan = dataclasses.replace(plan, infected=tuple(
                (s.name, tuple(sorted(runs))) for s, runs in zip(judge.scenarios, infected)))
        return plan, verdicts
    chosen = list(unit_ids)
    local = None
    infection = planned.infection(judge.scenarios) if planned is not None else None
    if infection is not None:
        local = tuple(frozenset(k + 1 for k, m in enumerate(chosen) if unit_ids[m] in runs) for runs in infection)
    return plan, _judged(judge, chosen, jobs, progress, local)[0]


def _mutant_side_factories(backend: str, iec) -> tuple[Callable, Callable | None]:
    """How a mutant's ST text becomes an executor on the chosen backend, and how one build of the text with every
    mutation as a switch (mutant schemata) does."""
    if backend == "matiec":
        from transpiler.backends.st.check import find_iec2c
        from transpiler.exec.compiled.matiec_schema import MatiecSchema
        from transpiler.exec.compiled.matiec_side import matiec_side_factory
        iec2c = find_iec2c()
        return ((lambda text: matiec_side_factory(text, iec, iec2c)),
                (lambda text, mutations: MatiecSchema(text, mutations, iec, iec2c)))
    from transpiler.verify.cosim import BuiltinSchema, builtin_side_factory
    return ((lambda text: builtin_side_factory(text, "project.st")),
            (lambda text, mutations: BuiltinSchema(text, mutations, "project.st")))


def _judged(judge, mutants: list, jobs: int, progress: Callable[[int, int], None] | None,
            infected: tuple | None = None, indexes: list[int] | None = None) -> tuple[list, tuple | None]:
    """The verdicts of `mutants` (of those at `indexes` only, when given; see verify/mutate.py judge_all) and the
    infection map the probing found (None without a schema); `infected` is a plan file's map, which skips the
    probing. Raises CompileFailed when the unmutated translation does not agree with the reference."""
    from transpiler.verify.mutate import judge_all, prepare
    judging = prepare(judge, mutants, jobs, infected)
    if judging.problems:
        raise _usage("the unmutated translation is not equivalent under the stimulus, mutation results "
                     "would mean nothing (run hh2iec equiv): " + "; ".join(judging.problems[:5]))
    verdicts = []
    total = len(mutants) if indexes is None else len(indexes)
    for verdict in judge_all(judge, mutants, jobs, judging, indexes):
        verdicts.append(verdict)
        if progress is not None:
            progress(len(verdicts), total)
    return verdicts, judging.infected


def mutate(project: Project, *, scenarios: Iterable[Path] = (), random_cycles: int = 2000, seed: int = 1,
           backend: str = "auto", mp_file: Path | None = None, jobs: int = 1, count: int = 0,
           equivalent_file: Path | None = None, mutants_file: Path | None = None,
           progress: Callable[[int, int], None] | None = None, share: Share = EVERYTHING) -> Mutation:
    """Mutants of the emitted ST judged by co-simulation under the scenarios and `random_cycles` of
    coverage-guided stimulus (see verify/mutate.py); `count` > 0 judges a seeded sample spread over the
    operators, `mutants_file` (the --survivors format) only the mutants it lists; `equivalent_file` lists mutants
    judged equivalent, which leave the denominator. Raises CompileFailed on bad input, or when the unmutated
    translation is not equivalent under the stimulus. `share`: as for check_equivalence, over the mutants."""
    import os
    import tempfile
    import time
    from transpiler.verify.equiv import choose_backend
    from transpiler.verify.mutate import Judge, MutationResult, apply_equivalents, choose, load_equivalents, mutation_sites
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
    side_factory, schema_factory = _mutant_side_factories(chosen.name, iec)
    names = project_names(project.program)
    loaded = _load_scenarios(project, scenarios, names, diags)
    users = list(loaded)                    # the user's scenarios, before the generated ones join them
    base_mp = mp if mp_path is not None else None      # None: the project has no machine data of its own
    digest, generated, search_seconds, planned = _mutation_runs(project, names, loaded, mp_path, base_mp, scenarios,
                                                       equivalent_file, mutants_file,
                                                       (random_cycles, seed, backend, count), share)
    loaded += generated
    from transpiler.backends.report.report import io_map_of
    judge = Judge(project.program, io_map_of(transpiled.result), names, sorted(loaded, key=lambda s: s.cycles),
                  st_text, side_factory, compile_program(project.program), base_mp, schema_factory,
                  isolate=chosen.name == "matiec")
    saved_cache = os.environ.get("HH2IEC_CACHE")
    with tempfile.TemporaryDirectory(prefix="hh2iec-mutants-") as cache:
        # Mutant libraries are throw-away: they stay out of the user's build cache.
        os.environ["HH2IEC_CACHE"] = cache
        try:
            sites = mutation_sites(st_text)
            mutants = [m for m in choose(sites, count, seed) if listed is None or m.key in listed]
            plan, unit_ids = _mutation_plan(digest, mutants, judge.scenarios, generated, search_seconds, share)
            start = time.perf_counter()
            plan, verdicts = _judge_share(judge, plan, mutants, unit_ids, share, planned, jobs, progress)
            mutants = list(unit_ids)
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
    return Mutation(result, st_text, chosen.note, tuple(diags.items) + tuple(chosen.diagnostics), plan, unit_ids)
