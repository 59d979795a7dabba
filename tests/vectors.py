"""The language test vectors (TV-nn) as the repository's own test data: tests/data/vectors/TV-nn.yaml, one file per
vector, copied once from section 20 of the public language description (see the README there). A missing or empty
folder is an error (VectorDataMissing), never a reason to skip."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import yaml

VECTOR_DIR = Path(__file__).resolve().parent / "data" / "vectors"
MIN_VECTORS = 80            # the description has 86; fewer means files were lost


class VectorDataMissing(RuntimeError):
    """The vector folder is missing, empty or short: a broken checkout, which must fail the tests."""


@dataclasses.dataclass(frozen=True)
class Vector:
    id: str
    data: dict[str, Any]

    @property
    def profile(self) -> str:
        return self.data.get("profile", "tv")

    @property
    def expect_error(self) -> dict | None:
        return self.data.get("expect_error")

    def write(self, folder: Path) -> Path:
        """Write the vector as a project folder; returns the main file."""
        folder.mkdir(parents=True, exist_ok=True)
        files = dict(self.data.get("files") or {})
        if "program" in self.data:
            files["main.src"] = self.data["program"]
        for name, text in files.items():
            (folder / name).write_text(text, encoding="latin-1")
        if "defs" in self.data:
            (folder / "vector_defs.def").write_text(self.data["defs"], encoding="latin-1")
        if "cfg" in self.data:
            (folder / "OEM.cfg").write_text(self.data["cfg"], encoding="latin-1")
        return folder / "main.src"

    def extra_defs(self, folder: Path) -> tuple[Path, ...]:
        return (folder / "vector_defs.def",) if "defs" in self.data else ()


def _number(path: Path) -> tuple[int, str]:
    match = re.fullmatch(r"TV-(\d+)", path.stem)
    return (int(match.group(1)) if match else 10 ** 9, path.stem)


def load_vectors(folder: Path = VECTOR_DIR) -> list[Vector]:
    """Every TV-nn.yaml of the folder, in id order. Raises VectorDataMissing when there are none (or too few)."""
    files = sorted(folder.glob("TV-*.yaml"), key=_number) if folder.is_dir() else []
    if len(files) < MIN_VECTORS:
        raise VectorDataMissing(f"expected at least {MIN_VECTORS} test vectors TV-nn.yaml in {folder}, found "
                                f"{len(files)}: the vectors are part of the repository, restore them (see its README.md)")
    vectors = []
    for path in files:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict) or data.get("id") != path.stem:
            raise VectorDataMissing(f"{path}: not a test vector whose id is the file name {path.stem}")
        vectors.append(Vector(data["id"], data))
    return vectors


def vector_scenario_yaml(vector: Vector) -> str:
    """The vector's stimulus as a scenario file (given -> initial, inputs -> per-cycle set events, nc, mp)."""
    data = vector.data
    cycles = int(data.get("cycles", 1))
    scenario: dict[str, Any] = {"name": vector.id, "cycles": cycles, "profile": vector.profile}
    if data.get("given"):
        scenario["initial"] = {str(k): v for k, v in data["given"].items()}
    events = []
    for name, values in (data.get("inputs") or {}).items():
        for cycle, value in enumerate(values):
            events.append({"cycle": cycle, "set": {str(name): value}})
    for action in data.get("nc") or []:
        action = dict(action)
        cycle = action.pop("cycle")
        events.append({"cycle": cycle, "nc": action})
    if events:
        scenario["events"] = sorted(events, key=lambda e: e["cycle"])
    if data.get("mp"):
        scenario["mp"] = {str(k): v for k, v in data["mp"].items()}
    return yaml.safe_dump(scenario, sort_keys=False)
