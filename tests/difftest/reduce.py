"""Reduction of a failing generated project to a minimal regression case (files, blocks, lines, cycles, stimulus) written into tests/regressions/."""

from __future__ import annotations

import dataclasses
import re
import tempfile
from pathlib import Path

import yaml

from transpiler.atomic import write_files_atomically
from transpiler.verify.cosim import cosimulate
from transpiler.verify.equiv import random_scenario, shrink
from transpiler.verify.stimulus import materialize_random, scenario_to_yaml

from .check import Verdict, check_files, prepare, side_factories

BLOCK = re.compile(r"^\s*;\s*@block\b")


@dataclasses.dataclass
class Case:
    """A project under reduction: its files and the stimulus length that shows the failure."""

    files: dict[str, str]
    main: str
    cfg: str | None
    mp: str | None
    cycles: int
    seed: int                       # seed of the random stimulus


class Reducer:
    """Greedy delta debugging: keep any smaller variant that still fails with the same signature."""

    def __init__(self, case: Case, target: Verdict, backends: tuple[str, ...], budget: int = 600):
        self.case = case
        self.target = target.signature
        self.backends = backends
        self.budget = budget
        self.runs = 0

    def fails(self, files: dict[str, str], cycles: int) -> bool:
        if self.runs >= self.budget:
            return False
        self.runs += 1
        c = self.case
        verdict = check_files(files, c.main, c.cfg if c.cfg in files else None, c.mp if c.mp in files else None,
                              cycles=cycles, seed=c.seed, backends=self.backends)
        return verdict.signature == self.target

    def reduce(self) -> Case:
        self._drop_files()
        for name in sorted(self.case.files):
            self._drop_chunks(name, blocks=True)
        for name in sorted(self.case.files):
            self._drop_chunks(name, blocks=False)
        self._drop_files()              # files emptied by the steps before
        return self.case

    def _try(self, files: dict[str, str]) -> bool:
        if self.fails(files, self.case.cycles):
            self.case = dataclasses.replace(self.case, files=files)
            return True
        return False

    def _drop_files(self) -> None:
        for name in sorted(self.case.files):
            if name != self.case.main:
                self._try({k: v for k, v in self.case.files.items() if k != name})

    def _drop_chunks(self, name: str, blocks: bool) -> None:
        """ddmin over the blocks (each from one `; @block` line to the next) or the single lines of one file."""
        units = _blocks(self.case.files[name]) if blocks else [[line] for line in self.case.files[name].splitlines()]
        chunk = max(1, len(units) // 2)
        while chunk >= 1:
            i, removed = 0, False
            while i < len(units):
                trial = units[:i] + units[i + chunk:]
                files = dict(self.case.files)
                files[name] = "".join(line + "\n" for unit in trial for line in unit)
                if self._try(files):
                    units = trial
                    removed = True
                else:
                    i += chunk
            if not removed:
                chunk //= 2
            if self.runs >= self.budget:
                return


def _blocks(text: str) -> list[list[str]]:
    """The lines before the first block, then every block (removable units; the prologue too, as one unit)."""
    units: list[list[str]] = [[]]
    for line in text.splitlines():
        if BLOCK.match(line):
            units.append([])
        units[-1].append(line)
    return [u for u in units if u]


def write_regression(case: Case, verdict: Verdict, backends: tuple[str, ...], folder: Path, origin: str) -> Path:
    """The reduced project and a shrunk stimulus as a scenario file; tests/test_regressions.py runs it from then on."""
    with tempfile.TemporaryDirectory(prefix="hh2iec-reg-") as tmp:
        root = Path(tmp)
        for name, text in case.files.items():
            (root / name).write_text(text, encoding="latin-1")
        mp = root / case.mp if case.mp and case.mp in case.files else None
        prepared = prepare(root / case.main, root / case.cfg if case.cfg in case.files else None, mp)
        scenario_yaml = ""
        if not isinstance(prepared, Verdict):
            scenario = random_scenario(prepared.program, prepared.names, case.cycles, case.seed, prepared.mp_path)
            scenario = materialize_random(scenario, prepared.names)
            factories = side_factories(prepared, backends)
            if not isinstance(factories, Verdict):
                for backend, factory in factories.items():
                    first = cosimulate(prepared.program, factory, prepared.iomap, scenario, prepared.names,
                                       compiled=prepared.compiled)
                    if first.divergence is not None:
                        scenario, _ = shrink(prepared.program, factory, prepared.iomap, scenario, prepared.names,
                                             first, prepared.compiled)
                        break
            named = scenario.model_copy(update={
                "name": folder.name,
                "machine_parameters": folder / case.mp if mp is not None else None})
            scenario_yaml = scenario_to_yaml(named, base_dir=folder)
    meta = {"main": case.main, "cfg": case.cfg if case.cfg in case.files else None, "found_by": origin,
            "status": verdict.status, "blame": verdict.blame, "detail": verdict.detail}
    out: dict[Path, bytes | str] = {folder / name: text.encode("latin-1") for name, text in case.files.items()}
    out[folder / "regression.yaml"] = yaml.safe_dump(meta, sort_keys=False)
    if scenario_yaml:
        out[folder / "scenario.yaml"] = scenario_yaml
    write_files_atomically(out)
    return folder
