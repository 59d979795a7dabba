"""Sharding: one check (equiv's runs, mutate's mutants) split over N independent jobs and merged back into one result.

There is no coordinator. Every shard loads the same inputs, lists the same units (runs or mutants) in the same order
with the same cost estimate, and computes the same partition alone (`partition`: longest processing time first over
that order); it then runs only the units assigned to it and writes its result with a `shard` section: which shard of
how many it was, the digest of the inputs (`inputs_digest`), the units it ran, and the raw material the merge needs to
recompute what is not a sum of per-unit results (the reference's coverage sets of each run, `encode_coverage`).
`check_shards` refuses a set of shard results that is not exactly shards 1..N of one set of inputs, each once."""

from __future__ import annotations

import dataclasses
import hashlib
import heapq
import json
import shlex
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

FORMAT = 1                  # version of the `shard` section and the plan file


@dataclasses.dataclass(frozen=True)
class ShardSpec:
    """Shard `index` (1-based) of `count`."""

    index: int
    count: int

    @classmethod
    def parse(cls, text: str) -> "ShardSpec":
        """`K/N` with 1 <= K <= N; ValueError with the reason otherwise."""
        k, slash, n = text.partition("/")
        if not slash or not k.strip().isdigit() or not n.strip().isdigit():
            raise ValueError(f"--shard expects K/N (shard K of N, e.g. 2/4), got '{text}'")
        spec = cls(int(k), int(n))
        if not 1 <= spec.index <= spec.count:
            raise ValueError(f"--shard {text}: K must be between 1 and N")
        return spec

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"


def partition(costs: Sequence[float], count: int) -> list[int]:
    """The shard (1..count) of each unit: the units in order of falling cost (position breaks ties) each go to the
    shard with the least cost so far (the lowest number breaks ties) -- the longest-processing-time rule, which keeps
    the largest shard within 4/3 of the best split. A function of the costs alone: every shard computes it alike."""
    if count < 1:
        raise ValueError("a partition needs at least one shard")
    assignment = [0] * len(costs)
    loads = [(0.0, shard) for shard in range(1, count + 1)]
    for position in sorted(range(len(costs)), key=lambda i: (-costs[i], i)):
        load, shard = heapq.heappop(loads)
        assignment[position] = shard
        heapq.heappush(loads, (load + costs[position], shard))
    return assignment


def shard_loads(costs: Sequence[float], assignment: Sequence[int], count: int) -> list[tuple[int, float]]:
    """(units, summed cost) per shard 1..count."""
    units = [0] * count
    loads = [0.0] * count
    for cost, shard in zip(costs, assignment):
        units[shard - 1] += 1
        loads[shard - 1] += cost
    return list(zip(units, loads))


def inputs_digest(command: str, version: str, files: Iterable[tuple[str, Path | str | None]],
                  settings: Mapping[str, Any]) -> str:
    """SHA-256 over everything a result depends on: the tool's version, the command, each input file's role and
    content (in order; a missing optional file counts as absent) and the settings that change results. Paths are
    not part of it: shards that check the project out into different folders still agree."""
    h = hashlib.sha256()

    def put(text: str) -> None:
        data = text.encode("utf-8")
        h.update(len(data).to_bytes(8, "big") + data)

    put(f"hh2iec {version} {command} shard-format {FORMAT}")
    for role, path in files:
        put(role)
        if path is None:
            put("<absent>")
        else:
            h.update(hashlib.sha256(Path(path).read_bytes()).digest())
    put(json.dumps({str(k): _plain(v) for k, v in settings.items()}, sort_keys=True))
    return h.hexdigest()


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (set, frozenset)):
        return sorted((_plain(v) for v in value), key=repr)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


# ---------------------------------------------------------------------------------------------
# Coverage sets as data: the merge recomputes the figures from the runs' sets, exactly as one process would


def encode_coverage(coverage: Any) -> dict[str, Any]:
    """A coverage record (a dataclass whose fields are sets of items or mappings from an item to a set) as JSON data,
    field by field, whatever fields it has: {"set": [item, ...]} or {"map": [[key, [item, ...]], ...]}, sorted."""
    out: dict[str, Any] = {}
    for field in dataclasses.fields(coverage):
        value = getattr(coverage, field.name)
        if isinstance(value, Mapping):
            out[field.name] = {"map": sorted([_json_item(k), sorted(_json_item(v) for v in values)]
                                             for k, values in value.items())}
        elif isinstance(value, (set, frozenset, tuple, list)):
            out[field.name] = {"set": sorted(_json_item(v) for v in value)}
        else:
            raise TypeError(f"coverage field {field.name} is neither a set nor a mapping of sets")
    return out


def decode_coverage(data: Mapping[str, Any], cls: type) -> Any:
    """The record encode_coverage wrote, as an instance of `cls` (items back to tuples, sets to frozensets)."""
    values = {}
    for field in dataclasses.fields(cls):
        entry = data.get(field.name)
        if entry is None:
            raise ValueError(f"the coverage data has no field '{field.name}' (written by another version?)")
        if "map" in entry:
            values[field.name] = {_item(k): frozenset(_item(v) for v in items) for k, items in entry["map"]}
        else:
            values[field.name] = frozenset(_item(v) for v in entry["set"])
    return cls(**values)


def _json_item(value: Any) -> Any:
    return [_json_item(v) for v in value] if isinstance(value, tuple) else value


def _item(value: Any) -> Any:
    return tuple(_item(v) for v in value) if isinstance(value, list) else value


# ---------------------------------------------------------------------------------------------
# The shard section and its checks


def shard_section(command: str, spec: ShardSpec, digest: str, version: str, argv: Sequence[str],
                  plan: tuple[Sequence[str], Sequence[float]], ran: Sequence[int], **extra: Any) -> dict[str, Any]:
    """The `shard` section of a shard's JSON result: enough to check a set of shards and to merge them. `plan` is
    the names and costs of every unit: shards that planned differently (another Python's generated runs, say) are
    told apart by its fingerprint even where the inputs' digest agrees."""
    names, costs = plan
    fingerprint = hashlib.sha256(json.dumps([list(names), list(costs)]).encode("utf-8")).hexdigest()
    return {"format": FORMAT, "command": command, "index": spec.index, "count": spec.count, "digest": digest,
            "plan": fingerprint, "version": version, "argv": list(argv), "units": len(names), "ran": list(ran),
            **extra}


class MergeRefused(ValueError):
    """The shard results cannot be merged into one result; `problems` says why, one line each."""

    def __init__(self, problems: list[str]):
        super().__init__("; ".join(problems))
        self.problems = problems


def check_shards(shards: Sequence[tuple[str, Mapping[str, Any]]]) -> Mapping[str, Any]:
    """The common shard section of (file name, JSON data) shard results that are shards 1..N of one command on one
    set of inputs, each given once and together running every unit once; raises MergeRefused with every problem."""
    problems: list[str] = []
    sections = []
    for name, data in shards:
        section = data.get("shard") if isinstance(data, Mapping) else None
        if not isinstance(section, Mapping) or section.get("format") != FORMAT:
            problems.append(f"{name}: not a shard result (no `shard` section of format {FORMAT}: "
                            "was it written with --shard K/N and --report?)")
            continue
        sections.append((name, section))
    if problems or not sections:
        raise MergeRefused(problems or ["no shard results given"])
    first_name, first = sections[0]
    for key, what in (("command", "command"), ("digest", "inputs (sources, scenarios, settings or hh2iec version)"),
                      ("count", "shard count N"),
                      ("plan", "plan (the same inputs gave other runs: give every shard the same --plan-file)")):
        for name, section in sections[1:]:
            if section.get(key) != first.get(key):
                problems.append(f"{name} and {first_name} differ in their {what}: "
                                f"{_short(section.get(key))} vs {_short(first.get(key))}")
    if problems:
        raise MergeRefused(problems)
    count = first["count"]
    by_index: dict[int, list[str]] = {}
    for name, section in sections:
        by_index.setdefault(section["index"], []).append(name)
    for index, names in sorted(by_index.items()):
        if len(names) > 1:
            problems.append(f"shard {index}/{count} is given {len(names)} times ({', '.join(names)})")
    missing = [k for k in range(1, count + 1) if k not in by_index]
    if missing:
        problems.append(f"shard{'s' if len(missing) > 1 else ''} {', '.join(f'{k}/{count}' for k in missing)} "
                        f"missing: the merged result would leave out {'their' if len(missing) > 1 else 'its'} units")
    if not problems:
        seen: dict[int, str] = {}
        for name, section in sections:
            for unit in section["ran"]:
                if unit in seen:
                    problems.append(f"unit {unit} was run by both {seen[unit]} and {name}")
                seen[unit] = name
        absent = sorted(set(range(1, first["units"] + 1)) - set(seen))
        if absent:
            problems.append(f"{len(absent)} of {first['units']} units were run by no shard (first: {absent[0]})")
    if problems:
        raise MergeRefused(problems)
    return first


def _short(value: Any) -> str:
    text = str(value)
    return text[:12] + "..." if len(text) > 15 else text


def reproduce_command(command: str, argv: Sequence[str], unit: int, plan_file: str | None = None) -> str:
    """The command line that runs one unit alone: the shard's own arguments with `--only UNIT`."""
    words = ["hh2iec", command, *argv]
    if plan_file is not None:
        words += ["--plan-file", plan_file]
    words += ["--only", str(unit)]
    return shlex.join(words)
