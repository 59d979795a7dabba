"""Sharding (verify/shard.py, `--shard K/N`, `--plan`, `--only`, `hh2iec merge`): the partition, the refusals, and
merged shard results that equal the unsharded run's (runs, verdict, coverage, killed mutants, JUnit) for N = 1, 2, 3
and 7 on a construct, and on the sample."""

from __future__ import annotations

import json
import re
import shlex
import shutil
from pathlib import Path

import pytest

from tests.shards import comparable, run_sharded
from transpiler.cli.app import main
from transpiler.exec.interp.machine import Coverage
from transpiler.verify.mutate import mutation_sites
from transpiler.verify.shard import (MergeRefused, ShardSpec, check_shards, decode_coverage, encode_coverage,
                                     partition, shard_loads)

ROOT = Path(__file__).resolve().parents[1]
COMPARE = ROOT / "samples" / "constructs" / "compare"
TIMERS = ROOT / "samples" / "constructs" / "timers"
SAMPLE = ROOT / "samples" / "basic_program"
EQUIV_ARGS = [str(COMPARE), "--scenario", str(COMPARE / "scenario.yaml"), "--random-cycles", "300",
              "--backend", "builtin"]
MUTATE_ARGS = [str(TIMERS), "--scenario", str(TIMERS / "scenario.yaml"), "--random-cycles", "300",
               "--backend", "builtin", "--equivalent", str(TIMERS / "equivalent_mutants.yaml"), "--jobs", "1"]


def _junit(path: Path) -> str:
    return re.sub(r'time="[0-9.]+"', "", path.read_text(encoding="utf-8"))


def _shards(command: str, args: list[str], n: int, folder: Path, plan: Path | None) -> list[Path]:
    reports = []
    for k in range(1, n + 1):
        report = folder / f"{command}-{n}-{k}.json"
        extra = ["--plan-file", str(plan)] if plan is not None else []
        assert main([command, *args, *extra, "--shard", f"{k}/{n}", "--report", str(report)]) in (0, 1)
        reports.append(report)
    return reports


# ---------------------------------------------------------------------------------------------
# the partition


def test_the_partition_is_the_longest_processing_time_rule_and_deterministic():
    costs = [5, 1, 8, 3, 3, 9, 2, 7, 1, 4]
    assignment = partition(costs, 3)
    assert assignment == partition(list(costs), 3)
    assert sorted(set(assignment)) == [1, 2, 3]
    loads = [load for _, load in shard_loads(costs, assignment, 3)]
    assert sum(loads) == sum(costs)
    # the largest first: 9 -> shard 1, 8 -> shard 2, 7 -> shard 3, then each to the least loaded
    assert assignment[5] == 1 and assignment[2] == 2 and assignment[7] == 3
    assert max(loads) - min(loads) <= max(costs)
    assert partition([1.0] * 5, 7) == [1, 2, 3, 4, 5]          # more shards than units: some shards run nothing
    assert partition([], 3) == []


@pytest.mark.parametrize("text", ["0/3", "4/3", "2", "a/b", "1/0", "-1/2"])
def test_a_bad_shard_spec_is_refused(text):
    with pytest.raises(ValueError):
        ShardSpec.parse(text)
    assert str(ShardSpec.parse("2/5")) == "2/5"


def test_coverage_sets_go_through_json_unchanged():
    cov = Coverage(frozenset({(0, 1), (2, 3)}), {(0, 4): frozenset({0, 1}), (1, 2): frozenset({-1, 3})})
    assert decode_coverage(json.loads(json.dumps(encode_coverage(cov))), Coverage) == cov


def _section(index, count=3, digest="d1", units=3, ran=None, command="equiv", plan="p1"):
    return {"shard": {"format": 1, "command": command, "index": index, "count": count, "digest": digest,
                      "plan": plan, "units": units, "ran": ran if ran is not None else [index], "argv": []}}


def test_check_shards_refuses_what_does_not_belong_together():
    good = [(f"s{k}.json", _section(k)) for k in (1, 2, 3)]
    assert check_shards(good)["count"] == 3
    cases = {
        "missing": (good[:2], "shard 3/3 missing"),
        "twice": ([*good, ("again.json", _section(2))], "shard 2/3 is given 2 times"),
        "digest": ([*good[:2], ("other.json", _section(3, digest="d2"))], "differ in their inputs"),
        "count": ([*good[:2], ("other.json", _section(3, count=4))], "shard count"),
        "command": ([*good[:2], ("other.json", _section(3, command="mutate"))], "differ in their command"),
        "not a shard": ([*good, ("plain.json", {"runs": []})], "not a shard result"),
        "unit twice": ([*good[:2], ("s3.json", _section(3, ran=[2]))], "unit 2 was run by both"),
        "plan": ([*good[:2], ("s3.json", _section(3, plan="p2"))], "differ in their plan"),
    }
    for name, (shards, message) in cases.items():
        with pytest.raises(MergeRefused) as refused:
            check_shards(shards)
        assert any(message in p for p in refused.value.problems), (name, refused.value.problems)


# ---------------------------------------------------------------------------------------------
# equiv on a construct: merged == unsharded


@pytest.fixture(scope="module")
def equiv_whole(tmp_path_factory):
    folder = tmp_path_factory.mktemp("equiv")
    assert main(["equiv", *EQUIV_ARGS, "--report", str(folder / "whole.json"),
                 "--junit", str(folder / "whole.xml")]) == 0
    assert main(["equiv", *EQUIV_ARGS, "--plan", "7", "--plan-file", str(folder / "plan.json")]) == 0
    return folder


@pytest.mark.parametrize("n", [1, 2, 3, 7])
def test_merged_equiv_shards_equal_the_unsharded_run(equiv_whole, n, capsys):
    folder = equiv_whole
    reports = _shards("equiv", EQUIV_ARGS, n, folder, folder / "plan.json")
    merged, junit = folder / f"merged-{n}.json", folder / f"merged-{n}.xml"
    assert main(["merge", *map(str, reversed(reports)), "--report", str(merged), "--junit", str(junit)]) == 0
    whole = comparable(folder / "whole.json")
    assert len(whole["runs"]) > 7                        # every shard of 7 has something to run
    assert comparable(merged) == whole
    assert whole["coverage"]["instructions_executed"] > 0 and whole["verdict"] == "EQUIVALENT"
    assert _junit(junit) == _junit(folder / "whole.xml")
    ran = [json.loads(r.read_text())["shard"]["ran"] for r in reports]
    assert sorted(u for units in ran for u in units) == list(range(1, len(whole["runs"]) + 1))
    assert "hh2iec merge: equiv EQUIVALENT" in capsys.readouterr().out


def test_the_plan_names_every_shard_and_its_runs(equiv_whole, capsys):
    assert main(["equiv", *EQUIV_ARGS, "--plan", "3"]) == 0
    out = capsys.readouterr().out
    runs = len(json.loads((equiv_whole / "whole.json").read_text())["runs"])
    assert f"equiv plan: {runs} runs" in out
    shares = [int(m) for m in re.findall(r"shard \d/3: (\d+) runs, about \d+ s", out)]
    assert len(shares) == 3 and sum(shares) == runs


def test_a_shard_missing_given_twice_or_of_other_inputs_is_refused(equiv_whole, tmp_path, capsys):
    reports = _shards("equiv", EQUIV_ARGS, 3, tmp_path, equiv_whole / "plan.json")
    capsys.readouterr()
    assert main(["merge", str(reports[0]), str(reports[2])]) == 2
    assert "error[E-SHARD]: shard 2/3 missing" in capsys.readouterr().err
    assert main(["merge", *map(str, reports), str(reports[1]), "--report", str(tmp_path / "m.json")]) == 2
    assert "shard 2/3 is given 2 times" in capsys.readouterr().err
    assert not (tmp_path / "m.json").exists()
    other = tmp_path / "other.json"
    assert main(["equiv", *EQUIV_ARGS[:-2], "--backend", "auto", "--plan-file", str(equiv_whole / "plan.json"),
                 "--shard", "2/3", "--report", str(other)]) == 2
    err = capsys.readouterr().err
    assert "error[E-SHARD]" in err and "made from other inputs" in err
    seeded = [tmp_path / "seed2.json"]
    assert main(["equiv", *EQUIV_ARGS, "--seed", "2", "--random-cycles", "0", "--shard", "2/3",
                 "--report", str(seeded[0])]) in (0, 1)
    capsys.readouterr()
    assert main(["merge", str(reports[0]), str(seeded[0]), str(reports[2])]) == 2
    assert "differ in their inputs" in capsys.readouterr().err
    assert main(["merge", str(equiv_whole / "whole.json")]) == 2
    assert "not a shard result" in capsys.readouterr().err
    assert main(["equiv", *EQUIV_ARGS, "--shard", "1/2"]) == 2
    assert "--shard needs --report" in capsys.readouterr().err


def test_a_shard_with_a_plan_file_loads_only_the_runs_it_makes(equiv_whole, tmp_path, monkeypatch, capsys):
    """The plan job loaded and checked every run; a shard parses its own share only (its set-up does not grow with
    the other shards' scenarios), and its result is the same as when it loaded everything."""
    from transpiler.verify import scenario as scenario_module
    parsed: list[str] = []
    real = scenario_module.scenario_from_text

    def counting(text, source, *args, **kwargs):
        parsed.append(str(source))
        return real(text, source, *args, **kwargs)

    monkeypatch.setattr(scenario_module, "scenario_from_text", counting)
    plan = json.loads((equiv_whole / "plan.json").read_text())
    report = tmp_path / "shard.json"
    assert main(["equiv", *EQUIV_ARGS, "--plan-file", str(equiv_whole / "plan.json"), "--shard", "2/7",
                 "--report", str(report)]) == 0
    ran = json.loads(report.read_text())["shard"]["ran"]
    assert 0 < len(ran) < len(plan["units"]) and len(parsed) == len(ran)
    reference = _shards("equiv", EQUIV_ARGS, 7, tmp_path, equiv_whole / "plan.json")[1]
    assert comparable(report) == comparable(reference)


def test_a_damaged_plan_file_is_refused(equiv_whole, tmp_path, capsys):
    plan = json.loads((equiv_whole / "plan.json").read_text())
    for damage in ({"cost": "many"}, {"unit": 99}, {"name": None}):
        broken = tmp_path / "plan.json"
        units = [dict(u) for u in plan["units"]]
        units[1].update(damage)
        broken.write_text(json.dumps({**plan, "units": units}))
        assert main(["equiv", *EQUIV_ARGS, "--plan-file", str(broken), "--shard", "1/2",
                     "--report", str(tmp_path / "r.json")]) == 2
        assert "error[E-SHARD]" in capsys.readouterr().err and not (tmp_path / "r.json").exists()
    broken.write_text(json.dumps({**plan, "units": plan["units"][:-1]}))
    assert main(["equiv", *EQUIV_ARGS, "--plan-file", str(broken), "--shard", "1/2",
                 "--report", str(tmp_path / "r.json")]) == 2
    assert "make it again" in capsys.readouterr().err


def test_merge_refuses_sources_that_changed_since_the_shards_ran(tmp_path, capsys):
    project = tmp_path / "timers"
    shutil.copytree(TIMERS, project)
    args = [str(project), "--scenario", str(project / "scenario.yaml"), "--backend", "builtin"]
    reports = _shards("equiv", args, 2, tmp_path, None)
    main_src = project / "main.src"
    main_src.write_text(main_src.read_text() + "\n; edited after the shards ran\n")
    capsys.readouterr()
    assert main(["merge", *map(str, reports)]) == 2
    assert "not the ones the shards ran on" in capsys.readouterr().err


def test_a_divergence_is_named_with_the_command_that_reproduces_it_alone(tmp_path, capsys):
    assert main(["transpile", str(COMPARE), "--out", str(tmp_path / "out"), "--format", "st"]) == 0
    st = (tmp_path / "out" / "project.st").read_text()
    wrong = tmp_path / "wrong.st"
    wrong.write_text(next(m for m in mutation_sites(st) if m.operator == "comparison").apply(st))
    shutil.copy(tmp_path / "out" / "io_map.csv", tmp_path / "io_map.csv")
    args = [*EQUIV_ARGS, "--st", str(wrong), "--no-shrink"]
    whole = tmp_path / "whole.json"
    assert main(["equiv", *args, "--report", str(whole)]) == 1
    plan = tmp_path / "plan.json"
    assert main(["equiv", *args, "--plan", "3", "--plan-file", str(plan)]) == 0
    reports = _shards("equiv", args, 3, tmp_path, plan)
    merged = tmp_path / "merged.json"
    capsys.readouterr()
    assert main(["merge", *map(str, reports), "--report", str(merged)]) == 1
    assert "NOT EQUIVALENT" in capsys.readouterr().out
    # the shards' reproduce lines name the plan file they took the generated runs from; the rest is the same
    assert _unreproduced(merged) == _unreproduced(whole)
    data = json.loads(merged.read_text())
    failures = data["shard"]["failures"]
    assert failures and all(f["reproduce"].startswith("hh2iec equiv ") for f in failures)
    first = failures[0]
    words = shlex.split(first["reproduce"])
    assert words[-4:] == ["--plan-file", str(plan), "--only", str(first["run"])] and "--shard" not in words
    alone = tmp_path / "alone.json"
    assert main([*words[1:], "--report", str(alone)]) == 1
    (run,) = _unreproduced(alone)["runs"]
    assert run == next(r for r in _unreproduced(whole)["runs"] if r["run"] == first["run"])


def _unreproduced(report: Path) -> dict:
    data = comparable(report)
    for run in data["runs"]:
        run.pop("reproduce", None)
    return data


# ---------------------------------------------------------------------------------------------
# mutate on a construct: merged == unsharded


@pytest.fixture(scope="module")
def mutate_whole(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mutate")
    assert main(["mutate", *MUTATE_ARGS, "--report", str(folder / "whole.json"),
                 "--junit", str(folder / "whole.xml")]) == 0
    assert main(["mutate", *MUTATE_ARGS, "--plan", "3", "--plan-file", str(folder / "plan.json")]) == 0
    return folder


@pytest.mark.parametrize("n", [1, 2, 3, 7])
def test_merged_mutate_shards_equal_the_unsharded_run(mutate_whole, n, capsys):
    folder = mutate_whole
    reports = _shards("mutate", MUTATE_ARGS, n, folder, folder / "plan.json")
    merged, junit = folder / f"merged-{n}.json", folder / f"merged-{n}.xml"
    assert main(["merge", *map(str, reports), "--report", str(merged), "--junit", str(junit)]) == 0
    whole = comparable(folder / "whole.json")
    assert whole["counts"]["killed"] > 7 and whole["counts"]["equivalent"] > 0
    assert comparable(merged) == whole
    assert _junit(junit) == _junit(folder / "whole.xml")
    assert "hh2iec merge: mutate score 100.0%" in capsys.readouterr().out
    assert main(["merge", *map(str, reports), "--min-score", "1.0"]) == 0
    assert json.loads(reports[0].read_text())["shard"]["min_score"] == 0.9


def test_a_mutate_shard_takes_the_infection_map_from_the_plan_file(mutate_whole, tmp_path, monkeypatch, capsys):
    """The plan job probed every run with every mutant; a shard given its plan file does not probe again and
    records the reference only of the runs its own mutants go through, with the verdicts of the whole run."""
    from transpiler.verify import mutate as mutate_module
    plan = json.loads((mutate_whole / "plan.json").read_text())
    infected = plan["infected"]
    assert infected and all(set(e) == {"run", "mutants"} for e in infected)
    assert {n for e in infected for n in e["mutants"]} <= set(range(1, len(plan["units"]) + 1))
    recorded: list[str] = []
    real = mutate_module.record_reference
    monkeypatch.setattr(mutate_module, "record_reference",
                        lambda program, iomap, scenario, *a, **k: recorded.append(scenario.name) or real(
                            program, iomap, scenario, *a, **k))
    probes: list = []
    monkeypatch.setattr(mutate_module, "_prepare_scenario", lambda *a: probes.append(a))
    report = tmp_path / "shard.json"
    assert main(["mutate", *MUTATE_ARGS, "--plan-file", str(mutate_whole / "plan.json"), "--shard", "2/7",
                 "--report", str(report)]) == 0
    assert not probes and len(set(recorded)) == len(recorded) < len(infected)
    whole = {m["unit"]: m for m in comparable(mutate_whole / "whole.json")["mutants"]}
    shard = comparable(report)["mutants"]
    assert shard and all(m == whole[m["unit"]] for m in shard)
    broken = tmp_path / "plan.json"
    broken.write_text(json.dumps({**plan, "infected": [{**infected[0], "mutants": [0]}, *infected[1:]]}))
    capsys.readouterr()
    assert main(["mutate", *MUTATE_ARGS, "--plan-file", str(broken), "--shard", "2/7",
                 "--report", str(tmp_path / "r.json")]) == 2
    assert "infection map does not fit" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# the sample, and the recipe's processes


def test_sample_equiv_and_mutate_shards_merge_to_the_unsharded_result(tmp_path):
    # the sample's shortest scenarios: the set-up of each shard (reading and translating the sample) is the point
    scenarios = [SAMPLE / "scenarios" / f"{name}.yaml" for name in (
        "init_spindle_tool_negative", "init_first_cycle_m_strobe_held", "machine_data_startup",
        "power_on_dirty_counters", "gear_code_invalid")]
    base = [str(SAMPLE / "Main_PGM.src"), *(a for s in scenarios for a in ("--scenario", str(s))),
            "--random-cycles", "0", "--backend", "builtin"]
    assert main(["equiv", *base, "--report", str(tmp_path / "whole.json")]) == 0
    reports = _shards("equiv", base, 4, tmp_path, None)
    assert main(["merge", *map(str, reports), "--report", str(tmp_path / "merged.json")]) == 0
    assert comparable(tmp_path / "merged.json") == comparable(tmp_path / "whole.json")
    mutate = [*base, "--count", "4", "--jobs", "1", "--min-score", "0"]
    assert main(["mutate", *mutate, "--report", str(tmp_path / "mwhole.json")]) == 0
    reports = _shards("mutate", mutate, 4, tmp_path, None)
    assert main(["merge", *map(str, reports), "--report", str(tmp_path / "mmerged.json")]) == 0
    whole = comparable(tmp_path / "mwhole.json")
    assert whole["judged"] == 4 and comparable(tmp_path / "mmerged.json") == whole


def test_the_make_shards_recipe_runs_parallel_processes_and_merges(tmp_path):
    """What `make shards` runs (tests/shards.py), on a construct: plan, two shard processes at once, merge."""
    args = [str(TIMERS), "--scenario", str(TIMERS / "scenario.yaml"), "--random-cycles", "200",
            "--backend", "builtin"]
    run = run_sharded("equiv", args, 2, tmp_path / "shards")
    assert run.shard_codes == [0, 0] and run.merge_code == 0, run.output
    assert "hh2iec merge: equiv EQUIVALENT" in run.output
    merged = json.loads(run.merged.read_text())
    assert merged["shard"]["merged"] == 2 and merged["verdict"] == "EQUIVALENT"


def test_difftest_shards_deal_out_the_programs_once_each():
    import argparse
    from tests.difftest.run import jobs_for, main as difftest_main
    base = dict(count=10, seed=3, size=20, cycles=50, backends="builtin", matiec_every=10, only=None)
    whole = [job.program_seed for job in jobs_for(argparse.Namespace(**base, shard=None))]
    shares = [[job.program_seed for job in jobs_for(argparse.Namespace(**base, shard=ShardSpec(k, 3)))]
              for k in (1, 2, 3)]
    assert sorted(s for share in shares for s in share) == whole and all(shares)
    with pytest.raises(SystemExit):
        difftest_main(["--count", "2", "--shard", "4/3"])
