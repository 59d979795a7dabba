"""One differential check: a project through the front end, the ST backend and the co-simulation on every ST executor, with a verdict and who is to blame."""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path
from typing import Callable

from transpiler.verify.cosim import CosimResult, Divergence, builtin_side_factory, cosimulate
from transpiler.diagnostics import CompileFailed, Diagnostics
from transpiler.verify.equiv import random_scenario
from transpiler.frontend.load import ProjectOptions
from transpiler.exec.interp import CompiledProgram, compile_program
from transpiler.ir import Program
from transpiler.backends.report.iomap import IoMap
from transpiler.frontend.pipeline import compile_project
from transpiler.verify.scenario import NameTable, Scenario
from transpiler.language.semantics import make_semantics
from transpiler.verify.simulate import build_machine, project_names
from transpiler.verify.simulate import run_scenario as simulate
from transpiler.backends.st.check import find_iec2c
from transpiler.exec.stexec.typesys import STR_MAX
from transpiler.backends.transpile import Transpiled, transpile_program
from transpiler.backends.report.report import io_map_of
from transpiler.frontend.mpfile import read_mp_file

# Verdicts. "invalid" means the project is not a well-defined program (front-end errors or a runtime fault of the
# reference interpreter): the generator is to blame, not the translator.
# "target limit": the translated program behaves as written, but a value exceeds what the target holds (a string
# longer than matiec's 126 characters, reported in report.md under "Target limits"); neither side is to blame.
OK, MISMATCH, INVALID, ERROR, TARGET_LIMIT = "ok", "mismatch", "invalid", "error", "target limit"
PASSING = frozenset({OK, TARGET_LIMIT})


@dataclasses.dataclass(frozen=True)
class Verdict:
    status: str
    blame: str = ""              # translator, built-in executor, matiec, generator, tool
    detail: str = ""
    cycles: int = 0              # cycles compared (the shorter run when there are two executors)
    divergence_cycle: int | None = None

    @property
    def signature(self) -> tuple[str, str]:
        """What a reduced case must keep showing to count as the same failure."""
        return self.status, self.blame


@dataclasses.dataclass
class Prepared:
    program: Program
    transpiled: Transpiled
    names: NameTable
    iomap: IoMap
    mp_path: Path | None
    compiled: CompiledProgram           # the reference side, compiled once for every run of this project


def prepare(main: Path, cfg: Path | None, mp_path: Path | None) -> Prepared | Verdict:
    """Front end and ST backend; a project they reject is a Verdict (invalid input or a translator gap)."""
    result = compile_project(ProjectOptions(main=main, cfg=cfg), make_semantics("itnc530", {}))
    if not result.ok:
        first = next((d.render() for d in result.diagnostics.items if d.severity == "error"), "front-end error")
        return Verdict(INVALID, "generator", first)
    diags = Diagnostics()
    mp = read_mp_file(mp_path, diags) if mp_path else {}
    try:
        transpiled = transpile_program(result.program, diags, mp, {"st"})
    except Exception as exc:  # noqa: BLE001 - a crash of the backend is the finding
        return Verdict(ERROR, "translator", f"ST backend crashed: {type(exc).__name__}: {exc}")
    if transpiled.result.untranslated:
        _, what = transpiled.result.untranslated[0]
        return Verdict(ERROR, "translator", f"not translated: {what}")
    return Prepared(result.program, transpiled, project_names(result.program), io_map_of(transpiled.result),
                    mp_path, compile_program(result.program))


def side_factories(prepared: Prepared, backends: tuple[str, ...]) -> dict[str, Callable] | Verdict:
    factories: dict[str, Callable] = {}
    st_text = prepared.transpiled.st_text
    for backend in backends:
        try:
            if backend == "builtin":
                factories[backend] = builtin_side_factory(st_text)
            else:
                from transpiler.exec.compiled.matiec_side import matiec_side_factory
                factories[backend] = matiec_side_factory(st_text, prepared.transpiled.result.project, find_iec2c())
        except CompileFailed as exc:
            first = exc.diagnostics[0].render() if exc.diagnostics else str(exc)
            return Verdict(ERROR, "translator", f"the built-in executor rejects the emitted ST: {first}")
        except Exception as exc:  # noqa: BLE001 - e.g. iec2c rejecting the emitted ST: a translator finding
            return Verdict(ERROR, "translator" if backend == "matiec" else "built-in executor",
                           f"{backend} cannot build the emitted ST: {str(exc)[:300]}")
    return factories


def reference_fault(prepared: Prepared, scenario: Scenario) -> str | None:
    """The first runtime fault of the reference interpreter alone under the scenario (None: well defined)."""
    fault = simulate(prepared.program, scenario, prepared.names, machine=build_machine(
        prepared.program, scenario, Diagnostics(), compiled=prepared.compiled)).fault
    return None if fault is None else f"{fault.code} in cycle {fault.cycle}: {fault.message}"


def available_backends() -> tuple[str, ...]:
    return ("builtin", "matiec") if find_iec2c() is not None else ("builtin",)


def run_scenario(prepared: Prepared, factories: dict[str, Callable], scenario: Scenario) -> Verdict:
    """Co-simulate on every executor and decide who is to blame from how the executors agree."""
    results: dict[str, CosimResult] = {}
    for backend, factory in factories.items():
        results[backend] = cosimulate(prepared.program, factory, prepared.iomap, scenario, prepared.names,
                                      compiled=prepared.compiled)
    return judge(results)


def judge(results: dict[str, CosimResult]) -> Verdict:
    cycles = min(r.cycles_run for r in results.values())
    for r in results.values():
        # A fault of the reference interpreter happens before the ST side runs that cycle: the program is ill-defined.
        if r.error_side == "original":
            return Verdict(INVALID, "generator", f"reference interpreter: {r.error}", cycles)
    bad = {b: r for b, r in results.items() if not r.equivalent}
    if not bad:
        return Verdict(OK, cycles=cycles)
    first_backend, first = next(iter(bad.items()))
    detail = _describe(first_backend, first)
    if all(_string_cut(r.divergence) for r in bad.values()):
        return Verdict(TARGET_LIMIT, "", detail, cycles, first.divergence.cycle)
    if len(results) == 1:
        blame = "translator or built-in executor" if first_backend == "builtin" else "translator or matiec"
    elif len(bad) == len(results):
        blame = "translator"        # both executors agree with each other and not with the reference
    else:
        blame = "built-in executor" if first_backend == "builtin" else "matiec"
    status = MISMATCH if first.divergence is not None else ERROR
    return Verdict(status, blame, detail, cycles, first.divergence.cycle if first.divergence else None)


def _string_cut(d: Divergence | None) -> bool:
    """The translated string is the original one cut at the target's string length."""
    return (d is not None and isinstance(d.original, str) and isinstance(d.translated, str)
            and len(d.original) > STR_MAX and d.translated == d.original[:STR_MAX])


def _describe(backend: str, result: CosimResult) -> str:
    d = result.divergence
    if d is not None:
        return (f"{backend}: cycle {d.cycle}: {d.name} ({d.operand}) original {d.original!r}, "
                f"translated {d.translated!r}")
    return f"{backend}: {result.error}"


def check_files(files: dict[str, str], main: str, cfg: str | None, mp: str | None, *, cycles: int, seed: int,
                backends: tuple[str, ...], scenario_of: Callable[[Prepared], Scenario] | None = None) -> Verdict:
    """Write the project to a temporary folder and check it; `scenario_of` replaces the random stimulus."""
    with tempfile.TemporaryDirectory(prefix="hh2iec-diff-") as tmp:
        root = Path(tmp)
        for name, text in files.items():
            (root / name).write_text(text, encoding="latin-1")
        prepared = prepare(root / main, root / cfg if cfg else None, root / mp if mp else None)
        if isinstance(prepared, Verdict):
            return prepared
        scenario = (scenario_of(prepared) if scenario_of is not None
                    else random_scenario(prepared.program, prepared.names, cycles, seed, prepared.mp_path))
        factories = side_factories(prepared, backends)
        if isinstance(factories, Verdict):
            # The translation failed before anything ran: it only counts for a program that is well defined.
            fault = reference_fault(prepared, scenario)
            return factories if fault is None else Verdict(INVALID, "generator", f"reference interpreter: {fault}")
        return run_scenario(prepared, factories, scenario)
