"""Loads the public test vectors of spec section 20 from the shared spec at test time and writes them as projects."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import yaml

SPEC = Path(__file__).resolve().parents[2] / "shared" / "spec" / "heidenhain-plc.md"
SKIP_REASON = f"the shared language spec is not available at {SPEC}"


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


def load_vectors() -> list[Vector]:
    text = SPEC.read_text(encoding="utf-8")
    start = text.index("## 20. Semantics test vectors")
    vectors = []
    for block in re.findall(r"```yaml\n(.*?)```", text[start:], re.S):
        data = yaml.safe_load(block)
        if isinstance(data, dict) and str(data.get("id", "")).startswith("TV-"):
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
