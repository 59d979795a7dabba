"""Tests of scenario loading (schema, names, values, line numbers) and of the stimulus built from scenarios."""

from __future__ import annotations

import random
import textwrap
import time
from decimal import Decimal
from pathlib import Path

import pytest

from transpiler.diagnostics import CompileFailed, Diagnostics, Severity
from transpiler.verify.scenario import MAX_CYCLES, NameTable, OperandRef, Scenario, ScenarioError, bind, load_scenario
from transpiler.verify.stimulus import (ExpectationFailure, build_stimulus, check_expectations, materialize_random,
                                 observed_operands, scenario_to_yaml)

R = OperandRef

SYMBOLS = {
    "I_emergency": R("I", 0),
    "I_key_M3": R("I", 1),
    "I_key_M5": R("I", 2),
    "I_key_alias": R("I", 1),     # an & alias of I_key_M3
    "O_lamp": R("O", 5),
    "M_flag": R("M", 10),
    "B_byte": R("B", 10),
    "W_word": R("W", 20),
    "D_dword": R("D", 40),
    "S_text": R("S", 3),
    "I18": R("I", 18),            # a raw operand the program uses
}


@pytest.fixture
def names() -> NameTable:
    return NameTable.for_profile(SYMBOLS, "itnc530", writable_inputs=frozenset({"I19"}),
                                 non_toggle=frozenset({"I_key_alias", "K_max"}), constants=frozenset({"K_max"}))


def write(folder: Path, text: str, name: str = "scn.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
    return path


def errors_of(path: Path, names: NameTable) -> list:
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, names)
    return info.value.diagnostics


# ---------------------------------------------------------------------------------------------
# valid scenarios


def test_full_scenario_with_every_nc_action_loads(tmp_path: Path, names: NameTable) -> None:
    (tmp_path / "mp").mkdir()
    (tmp_path / "mp" / "machine.mp").write_text("MP 4110.0 : 1\n")
    sub = tmp_path / "scenarios"
    sub.mkdir()
    path = write(sub, """
        cycles: 300
        cycle_time_ms: 10
        profile: tnc426
        machine_parameters: ../mp/machine.mp
        mp:
          "4110.3": 0.5
          4110.10: 3
          "4120.0": 10
        initial: {I_emergency: 1, I3: 1}
        events:
          - {cycle: 10, set: {I_key_M3: 1, W_word: -1, S_text: "hello", D_dword: 4294967295}}
          - {cycle: 11, nc: {m_function: 3}}
          - {cycle: 12, nc: {spindle_speed: 1500}}
          - {cycle: 13, nc: {gear: 2}}
          - {cycle: 14, nc: {tool_call: {tool: 5, pocket: 2}}}
          - {cycle: 15, nc: {tool_call: {tool: 6, pocket: -1, second_strobe: true}}}
          - {cycle: 16, nc: {tool_def: {tool: 7, pocket: 4}}}
          - {cycle: 17, nc: {fn19: {value1: -5, value2: 100000}}}
          - {cycle: 18, nc: {mode: 5}}
          - {cycle: 19, nc: {restart: program}}
          - {cycle: 20, nc: {restart: machine_parameters}}
        random: {seed: 7, inputs: ["I_key_*", I18], toggle_probability: 0.05}
        observe: ["O*", M_flag]
        expect:
          - cycle: 30
            values: {O_lamp: 1}
        semantics: {chain_model: dynamic}
        module_results: {9100: [1, 2]}
        """)
    s = load_scenario(path, names)
    assert s.name == "scn"                      # default: the file name
    assert (s.cycles, s.cycle_time_ms, s.profile) == (300, 10, "tnc426")
    assert s.machine_parameters == (tmp_path / "mp" / "machine.mp").resolve()
    # an unquoted 4110.10 must not become 4110.1 (YAML would read it as a float)
    assert s.mp == {(4110, 3): Decimal("0.5"), (4110, 10): Decimal(3), (4120, 0): Decimal(10)}
    kinds = [e.nc.kind for e in s.events if e.nc is not None]
    assert kinds == ["m_function", "spindle_speed", "gear", "tool_call", "tool_call", "tool_def", "fn19", "mode",
                     "restart", "restart"]
    assert s.events[4].nc.as_dict() == {"tool_call": {"tool": 5, "pocket": 2, "second_strobe": False}}
    assert s.events[5].nc.tool_call.second_strobe is True
    assert s.events[10].nc.restart == "machine_parameters"
    assert s.semantics == {"chain_model": "dynamic"}
    assert s.module_results == {9100: [1, 2]}
    assert s.ref("I3") == R("I", 3) and s.ref("S_text") == R("S", 3)
    assert s.span_of("events", 4, "nc").line == 15


def test_defaults(tmp_path: Path, names: NameTable) -> None:
    s = load_scenario(write(tmp_path, "cycles: 5\n", "my_run.yaml"), names)
    assert (s.name, s.cycle_time_ms, s.profile, s.observe, s.random) == ("my_run", 20, "itnc530", None, None)


@pytest.mark.parametrize("name, value", [
    ("B_byte", -128), ("B_byte", 255), ("W_word", -32768), ("W_word", 65535),
    ("D_dword", -2 ** 31), ("D_dword", 2 ** 32 - 1), ("M_flag", 0), ("O_lamp", 1),
])
def test_range_limits_are_accepted(tmp_path: Path, names: NameTable, name: str, value: int) -> None:
    s = load_scenario(write(tmp_path, f"cycles: 2\ninitial: {{{name}: {value}}}\n"), names)
    assert s.initial == {name: value}


@pytest.mark.parametrize("text, ref", [("i 5", R("I", 5)), ("m1000", R("M", 1000)), ("W262", R("W", 262)),
                                       ("D100", R("D", 100)), ("S3", R("S", 3)), ("T 7", R("T", 7))])
def test_raw_operands_case_insensitive_with_optional_blank(tmp_path: Path, names: NameTable, text: str,
                                                           ref: OperandRef) -> None:
    value = '"x"' if ref.kind == "S" else "1"
    s = load_scenario(write(tmp_path, f'cycles: 2\ninitial: {{"{text}": {value}}}\n'), names)
    assert s.ref(text) == ref


# ---------------------------------------------------------------------------------------------
# malformed scenarios: every error class, with its line


MALFORMED = [
    ("yaml syntax", "cycles: 5\nname: a: b\nevents: []\n", 2, "YAML syntax"),
    ("unclosed flow", "cycles: 5\nevents: [\n  {cycle: 1\n", 4, "YAML syntax"),
    ("tab indentation", "cycles: 5\ninitial:\n\tI1: 1\n", 3, "YAML syntax"),
    ("unknown key", "cycles: 5\ncycle_tme_ms: 20\n", 2, "unknown key 'cycle_tme_ms'"),
    ("unknown nested key", "cycles: 5\nevents:\n  - cycle: 1\n    nc: {m_functon: 3}\n", 4, "unknown key 'm_functon'"),
    ("wrong type", "name: x\ncycles: ten\n", 2, "cycles"),
    ("string for integer", 'cycles: "5"\n', 1, "cycles"),
    ("missing cycles", "name: x\nevents: []\n", 1, "missing required key 'cycles'"),
    ("missing nested key", "cycles: 5\nevents:\n  - cycle: 1\n    nc: {tool_call: {tool: 5}}\n", 4, "'pocket'"),
    ("non-positive cycles", "name: x\ncycles: 0\n", 2, "cycles"),
    ("event after the end", "cycles: 5\nevents:\n  - cycle: 5\n    set: {I1: 1}\n", 3, "cycle 5"),
    ("expectation after the end", "cycles: 5\nexpect:\n  - cycle: 9\n    values: {O1: 1}\n", 3, "cycle 9"),
    ("unknown name", "cycles: 5\ninitial:\n  I_emergancy: 1\n", 3, "unknown name 'I_emergancy'"),
    ("unknown name in expect", "cycles: 5\nexpect:\n  - cycle: 1\n    values: {O_lamb: 1}\n", 4, "O_lamb"),
    ("unknown observe name", "cycles: 5\nobserve:\n  - M_flag\n  - M_flg\n", 4, "M_flg"),
    ("bit out of range", "cycles: 5\ninitial:\n  I1: 2\n", 3, "0 or 1"),
    ("byte out of range", "cycles: 5\ninitial:\n  B_byte: 256\n", 3, "8 bits"),
    ("negative byte out of range", "cycles: 5\ninitial:\n  B4: -129\n", 3, "8 bits"),
    ("word out of range", "cycles: 5\ninitial:\n  W_word: 65536\n", 3, "16 bits"),
    ("dword out of range", "cycles: 5\ninitial:\n  D_dword: 4294967296\n", 3, "32 bits"),
    ("negative dword out of range", "cycles: 5\ninitial:\n  D8: -2147483649\n", 3, "32 bits"),
    ("string into word", "cycles: 5\ninitial:\n  W_word: abc\n", 3, "integer"),
    ("number into string", "cycles: 5\ninitial:\n  S_text: 5\n", 3, "string"),
    ("float into bit", "cycles: 5\ninitial:\n  I1: 0.5\n", 3, "0 or 1"),
    ("address outside profile", "cycles: 5\ninitial:\n  M99999: 1\n", 3, "outside"),
    ("misaligned word", "cycles: 5\ninitial:\n  W3: 1\n", 3, "misaligned"),
    ("constant", "cycles: 5\ninitial:\n  K_max: 1\n", 3, "constant"),
    ("missing mp file", "cycles: 5\nmachine_parameters: nowhere.mp\n", 2, "not found"),
    ("bad mp key", 'cycles: 5\nmp:\n  "41a0.3": 1\n', 3, "4110.3"),
    ("bad mp value", 'cycles: 5\nmp:\n  "4110.3": fast\n', 3, "not a number"),
    ("duplicate key", "cycles: 5\ncycles: 6\n", 2, "duplicate key"),
    ("two nc actions", "cycles: 5\nevents:\n  - cycle: 1\n    nc: {m_function: 3, gear: 1}\n", 4, "exactly one"),
    ("empty event", "cycles: 5\nevents:\n  - cycle: 1\n", 3, "`set`, `nc` or `machine`"),
    ("axis out of range", "cycles: 5\nmachine:\n  axes: {16: {position: 1}}\n", 3, "less than 16"),
    ("unknown table", "cycles: 5\nmachine:\n  tables: [{table: X, line: 1, element: 1, value: 2}]\n", 3, "TCH"),
    ("table element out of range", "cycles: 5\nmachine:\n  tables: [{table: T, line: 1, element: 64, value: 2}]\n",
     3, "63"),
    ("empty machine", "cycles: 5\nevents:\n  - cycle: 1\n    machine: {}\n", 4, "`axes`, `drives`, `tables` or `status`"),
    ("status number out of range", "cycles: 5\nmachine:\n  status: {256: 1}\n", 3, "256"),
    ("bad restart", "cycles: 5\nevents:\n  - cycle: 1\n    nc: {restart: everything}\n", 4, "restart"),
    ("unknown profile", "cycles: 5\nprofile: tnc640\n", 2, "unknown profile"),
    ("probability above 1", "cycles: 5\nrandom: {seed: 1, inputs: [I1], toggle_probability: 1.5}\n", 2,
     "toggle_probability"),
    ("word in random inputs", "cycles: 5\nrandom:\n  seed: 1\n  inputs: [I1, W_word]\n", 4, "cannot toggle"),
    ("top level is a list", "- cycles: 5\n", 1, "mapping"),
]


@pytest.mark.parametrize("label, text, line, fragment", MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_scenario_gives_e_scenario_at_the_line(tmp_path: Path, names: NameTable, label: str, text: str,
                                                          line: int, fragment: str) -> None:
    path = write(tmp_path, text)
    diags = errors_of(path, names)
    errors = [d for d in diags if d.severity is Severity.ERROR]
    assert len(errors) == 1, [d.render() for d in diags]
    d = errors[0]
    assert d.code == "E-SCENARIO"
    assert (d.span.file, d.span.line) == (str(path), line), d.render()
    assert fragment in d.message, d.render()


def test_unknown_name_points_at_the_key_column(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, "cycles: 5\ninitial: {I1: 1, I_nope: 1}\n")
    (d,) = errors_of(path, names)
    assert (d.span.line, d.span.col) == (2, 18)
    assert d.render().startswith(f"{path}:2:18: error[E-SCENARIO]:")


def test_every_error_is_collected_in_one_raise(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 10
        colour: red
        initial: {I_unknown: 1}
        events:
          - cycle: 12
            set: {B_byte: 999}
          - cycle: 1
            nc: {gear: 1, mode: 2}
        profile: nope
        """)
    diags = errors_of(path, names)
    assert {d.span.line for d in diags} == {2, 3, 5, 6, 8, 9}
    assert all(d.code == "E-SCENARIO" for d in diags)


def test_scenario_error_is_a_compile_failure_with_rendered_lines(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, "cycles: -1\n")
    with pytest.raises(CompileFailed) as info:
        load_scenario(path, names)
    assert isinstance(info.value, ScenarioError)
    assert f"{path}:1:" in str(info.value) and "error[E-SCENARIO]" in str(info.value)


@pytest.mark.parametrize("content", ["", "# only a comment\n"])
def test_empty_file_is_an_error(tmp_path: Path, names: NameTable, content: str) -> None:
    (d,) = errors_of(write(tmp_path, content), names)
    assert "cycles" in d.message


def test_missing_or_undecodable_file_is_an_error_not_a_traceback(tmp_path: Path, names: NameTable) -> None:
    (d,) = errors_of(tmp_path / "absent.yaml", names)
    assert d.code == "E-SCENARIO" and d.span.file == str(tmp_path / "absent.yaml")
    bad = tmp_path / "latin1.yaml"
    bad.write_bytes(b"cycles: 5\nname: \xe9t\xe9\n")
    (d,) = errors_of(bad, names)
    assert d.code == "E-SCENARIO"


def test_bind_rejects_an_edited_scenario_with_an_unknown_name(tmp_path: Path, names: NameTable) -> None:
    s = load_scenario(write(tmp_path, "cycles: 5\ninitial: {I1: 1}\n"), names)
    edited = s.model_copy(update={"initial": {"I_gone": 1}})
    with pytest.raises(ScenarioError) as info:
        bind(edited, names)
    assert "I_gone" in info.value.diagnostics[0].message


# ---------------------------------------------------------------------------------------------
# stimulus


def test_writes_order_initial_then_sets_then_toggles_and_nc_actions(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 4
        initial: {I_emergency: 1, W_word: 7}
        events:
          - {cycle: 0, set: {W_word: 9}}
          - {cycle: 0, nc: {m_function: 3}}
          - {cycle: 2, set: {I_key_M5: 1}, nc: {tool_call: {tool: 5, pocket: 2}}}
        random: {seed: 3, inputs: [I18], toggle_probability: 1.0}
        """)
    st = build_stimulus(load_scenario(path, names), names)
    assert [(w.ref, w.value) for w in st.writes(0)] == [
        (R("I", 0), 1), (R("W", 20), 7), (R("W", 20), 9), (R("I", 18), 1)]
    assert st.nc_actions(0) == ({"m_function": 3},)
    assert st.nc_actions(1) == ()
    assert st.nc_actions(2) == ({"tool_call": {"tool": 5, "pocket": 2, "second_strobe": False}},)
    assert [(w.ref, w.value) for w in st.writes(2)] == [(R("I", 2), 1), (R("I", 18), 1)]


def test_toggle_flips_the_last_value_the_stimulus_drove(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 5
        initial: {I_key_M3: 1}
        events:
          - {cycle: 3, set: {I_key_M3: 1}}
        random: {seed: 1, inputs: [I_key_M3], toggle_probability: 1.0}
        """)
    st = build_stimulus(load_scenario(path, names), names)
    assert [[w.value for w in st.step(c).toggles] for c in range(5)] == [[0], [1], [0], [0], [1]]


def _reference_toggles(seed: int, inputs: list[OperandRef], probability: float, cycles: int) -> list[list]:
    # The documented algorithm, written out independently: one draw per input per cycle, inputs in name order.
    rng = random.Random(seed)
    state = {ref: 0 for ref in inputs}
    result = []
    for _ in range(cycles):
        row = []
        for ref in inputs:
            if rng.random() < probability:
                state[ref] ^= 1
                row.append((ref, state[ref]))
        result.append(row)
    return result


def test_random_stimulus_is_reproducible_and_follows_the_documented_draws(tmp_path: Path,
                                                                          names: NameTable) -> None:
    text = """
        cycles: 200
        random: {seed: SEED, inputs: ["I_key_*", I18, I19], toggle_probability: 0.5}
        """
    first = build_stimulus(load_scenario(write(tmp_path, text.replace("SEED", "42")), names), names)
    again = build_stimulus(load_scenario(write(tmp_path, text.replace("SEED", "42"), "b.yaml"), names), names)
    other = build_stimulus(load_scenario(write(tmp_path, text.replace("SEED", "43"), "c.yaml"), names), names)
    assert first.steps == again.steps
    assert first.steps != other.steps
    # I_key_alias is an alias and never toggles; names sort as I18 < I19 < I_key_M3 < I_key_M5
    assert [name for name, _ in first.toggled] == ["I18", "I19", "I_key_M3", "I_key_M5"]
    expected = _reference_toggles(42, [ref for _, ref in first.toggled], 0.5, 200)
    assert [[(w.ref, w.value) for w in first.step(c).toggles] for c in range(200)] == expected
    assert 0.4 < first.toggle_count / (200 * 4) < 0.6


def test_probability_zero_never_toggles(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, "cycles: 50\nrandom: {seed: 1, inputs: ['I*'], toggle_probability: 0}\n")
    assert build_stimulus(load_scenario(path, names), names).toggle_count == 0


def test_two_names_of_one_operand_toggle_it_once(tmp_path: Path) -> None:
    table = NameTable.for_profile({"I_a": R("I", 1), "I_b": R("I", 1)})
    path = write(tmp_path, "cycles: 3\nrandom: {seed: 1, inputs: ['I_*'], toggle_probability: 1.0}\n")
    st = build_stimulus(load_scenario(path, table), table)
    assert st.toggled == (("I_a", R("I", 1)),)
    assert [len(st.step(c).toggles) for c in range(3)] == [1, 1, 1]


def test_glob_matching_nothing_is_a_warning_with_its_line(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 3
        random:
          seed: 1
          inputs:
            - I18
            - "X_nothing_*"
            - "I_key_al*"
        """)
    st = build_stimulus(load_scenario(path, names), names)
    assert [(d.severity, d.code, d.span.line) for d in st.diagnostics] == [
        (Severity.WARNING, "E-SCENARIO-UNUSED", 6), (Severity.WARNING, "E-SCENARIO-UNUSED", 7)]
    assert "matches no name" in st.diagnostics[0].message
    assert st.toggled == (("I18", R("I", 18)),)


def test_explicit_alias_in_random_inputs_warns_and_is_not_toggled(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, "cycles: 3\nrandom: {seed: 1, inputs: [I_key_alias], toggle_probability: 1.0}\n")
    s = load_scenario(path, names)
    assert [d.severity for d in s.warnings] == [Severity.WARNING]
    assert build_stimulus(s, names).toggle_count == 0


def test_rebuilt_from_an_edited_scenario(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, "cycles: 10\nevents:\n  - {cycle: 8, set: {I1: 1}}\n  - {cycle: 2, set: {I2: 1}}\n")
    s = load_scenario(path, names)
    shorter = s.model_copy(update={"cycles": 5, "events": [s.events[1]]})
    st = build_stimulus(shorter, names)
    assert st.cycles == 5
    assert [(c, w.ref) for c in range(5) for w in st.writes(c)] == [(2, R("I", 2))]
    with pytest.raises(IndexError):
        st.writes(5)


def test_materialized_random_gives_the_same_writes(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 30
        initial: {I_key_M3: 1}
        events: [{cycle: 4, set: {I18: 1}}]
        random: {seed: 9, inputs: ["I_key_*", I18], toggle_probability: 0.3}
        """)
    s = load_scenario(path, names)
    plain = materialize_random(s, names)
    assert plain.random is None
    original, rebuilt = build_stimulus(s, names), build_stimulus(plain, names)
    assert original.toggle_count > 0 and rebuilt.toggle_count == 0
    for cycle in range(30):
        assert [w[:2] for w in original.writes(cycle)] == [w[:2] for w in rebuilt.writes(cycle)]


# ---------------------------------------------------------------------------------------------
# expectations and observed operands


def test_expectations_compare_modulo_width(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 5
        expect:
          - cycle: 2
            values: {B_byte: 0xFC, W_word: 65535, D_dword: -1, O_lamp: 1, S_text: "ok"}
          - cycle: 3
            values: {B_byte: -4}
        """)
    s = load_scenario(path, names)
    memory = {R("B", 10): -4, R("W", 20): -1, R("D", 40): 4294967295, R("O", 5): True, R("S", 3): "ok"}
    assert check_expectations(s, 2, memory.__getitem__) == []
    assert check_expectations(s, 1, lambda ref: 0) == []            # nothing expected in cycle 1
    memory[R("B", 10)] = 4
    memory[R("O", 5)] = 0
    failures = check_expectations(s, 2, memory.__getitem__)
    assert [(f.cycle, f.name, f.expected, f.actual) for f in failures] == [(2, "B_byte", 0xFC, 4), (2, "O_lamp", 1, 0)]
    assert isinstance(failures[0], ExpectationFailure) and failures[0].span.line == 4
    assert check_expectations(s, 3, lambda ref: 252) == []
    assert len(check_expectations(s, 3, lambda ref: 253)) == 1


def test_observed_operands_default_is_written_plus_outputs_with_symbol_names(tmp_path: Path,
                                                                              names: NameTable) -> None:
    s = load_scenario(write(tmp_path, "cycles: 2\n"), names)
    columns = observed_operands(s, names, written={R("W", 20), R("M", 10), R("M", 3), R("I", 1)},
                                outputs={R("O", 5), R("O", 1)})
    # I1 has the symbols I_key_M3 and I_key_alias: the first in sorted order wins
    assert columns == [("I_key_M3", R("I", 1)), ("O1", R("O", 1)), ("O_lamp", R("O", 5)), ("M3", R("M", 3)),
                       ("M_flag", R("M", 10)), ("W_word", R("W", 20))]


def test_observed_operands_follow_the_observe_globs(tmp_path: Path, names: NameTable) -> None:
    s = load_scenario(write(tmp_path, "cycles: 2\nobserve: ['O*', I18, 'I_key_*', 'Z*']\n"), names)
    diags = Diagnostics()
    columns = observed_operands(s, names, written={R("M", 10)}, outputs={R("O", 7)}, diagnostics=diags)
    assert columns == [("O_lamp", R("O", 5)), ("I18", R("I", 18)), ("I_key_M3", R("I", 1)), ("I_key_M5", R("I", 2))]
    assert [(d.code, d.span.line) for d in diags.warnings] == [("E-SCENARIO-UNUSED", 2)]


# ---------------------------------------------------------------------------------------------
# writing scenarios back


def test_scenario_to_yaml_round_trips(tmp_path: Path, names: NameTable) -> None:
    (tmp_path / "m.mp").write_text("MP 4110.0 : 1\n")
    path = write(tmp_path, """
        name: spindle
        cycles: 40
        machine_parameters: m.mp
        mp: {"4110.3": 0.1, "4110.10": 3, "7210": 0.125}
        initial: {I_emergency: 1, S_text: "a b"}
        events:
          - {cycle: 1, set: {B_byte: 0xFC, D_dword: -5}}
          - {cycle: 2, nc: {tool_call: {tool: 5, pocket: -1, second_strobe: true}}}
          - {cycle: 3, nc: {fn19: {value1: 1, value2: 2}}}
          - {cycle: 4, nc: {restart: machine_parameters}}
        random: {seed: 5, inputs: ["I_key_*"], toggle_probability: 0.25}
        observe: [O_lamp]
        expect: [{cycle: 9, values: {O_lamp: 1, S_text: "1"}}]
        semantics: {symbol_case: insensitive, cycle_time_ms: 10}
        module_results: {9100: [1, -2]}
        """)
    original = load_scenario(path, names)
    elsewhere = tmp_path / "out"
    elsewhere.mkdir()
    for base in (elsewhere, None):
        copy = write(elsewhere, scenario_to_yaml(original, base), "copy.yaml")
        again = load_scenario(copy, names)
        assert again == original
        assert again.machine_parameters.resolve() == (tmp_path / "m.mp").resolve()
    assert load_scenario(copy, names).mp[(7210, None)] == Decimal("0.125")


def test_scenario_built_in_code_round_trips(tmp_path: Path, names: NameTable) -> None:
    s = Scenario(cycles=3, events=[{"cycle": 1, "set": {"I1": 1}}])  # type: ignore[list-item]
    again = load_scenario(write(tmp_path, scenario_to_yaml(s)), names)
    assert again == s


@pytest.mark.parametrize("text, line, fragment", [
    ("cycles: !!int abc\n", 1, "bad value 'abc'"),
    ("cycles: 3\nname: x\x07\n", 2, "U+0007"),
])
def test_unreadable_values_give_one_message(tmp_path: Path, names: NameTable, text: str, line: int,
                                            fragment: str) -> None:
    (d,) = errors_of(write(tmp_path, text), names)
    assert d.span.line == line and fragment in d.message


def test_machine_data_loads_applies_per_cycle_and_round_trips(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 5
        machine:
          axes: {0: {position: 1250000}, 3: {active: false}}
          drives: {available: 5}
          tables:
            - {table: TCH, line: 4, element: 1, value: 12}
        events:
          - cycle: 2
            machine: {axes: {0: {position: -7}}}
        """)
    scenario = load_scenario(path, names)
    assert scenario.machine.axes[0].position == 1250000 and scenario.machine.axes[0].active
    assert not scenario.machine.axes[3].active and scenario.machine.axes[3].position == 0
    assert (scenario.machine.drives.available, scenario.machine.drives.switching_off) == (5, 0)
    assert scenario.machine.tables[0].table == "TCH"
    stimulus = build_stimulus(scenario, names)
    assert stimulus.machine_updates(1) == ()
    (update,) = stimulus.machine_updates(2)
    assert update.axes[0].position == -7
    again = write(tmp_path, scenario_to_yaml(scenario, tmp_path), "again.yaml")
    assert load_scenario(again, names) == scenario


# ---------------------------------------------------------------------------------------------
# hostile files (found by the scenario fuzzer, tests/fuzz.py): a bounded answer with the line, never a traceback


def _alias_bomb(levels: int) -> str:
    lines = ["lol0: &lol0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"lol{i}: &lol{i} [" + ", ".join([f"*lol{i - 1}"] * 10) + "]" for i in range(1, levels)]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("label, text, line, fragment", [
    ("billion laughs", "cycles: 5\n" + _alias_bomb(10), 1, "alias bomb"),
    ("an alias inside its own anchor", "cycles: 5\ninitial: &a {x: [*a]}\n", 2, "cannot contain itself"),
    ("nested 20000 levels", "cycles: 5\ninitial: " + "[" * 20_000 + "]" * 20_000 + "\n", 2, "deeper than 32"),
    ("mappings nested 5000 levels", "cycles: 5\nevents: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n", 2, "deeper"),
    ("block lists nested 3000 levels", "cycles: 5\nexpect:\n" + "- " * 3000 + "x\n", 3, "deeper than 32"),
    ("nested deeply by aliases", "cycles: 5\n" + "".join(
        f"a{i}: &a{i} [[[[[[[[[[{f'*a{i - 1}' if i else 0}]]]]]]]]]]\n" for i in range(8)), 1, "aliases expanded"),
    ("cycles beyond the limit", "cycles: 99999999999999\n", 1, "more than a scenario file may run"),
    ("cycles one beyond the limit", f"cycles: {MAX_CYCLES + 1}\n", 1, f"({MAX_CYCLES} cycles)"),
])
def test_hostile_scenario_is_refused_at_its_line(tmp_path: Path, names: NameTable, label: str, text: str, line: int,
                                                 fragment: str) -> None:
    path = write(tmp_path, text)
    started = time.perf_counter()
    diags = errors_of(path, names)
    assert time.perf_counter() - started < 5, label
    assert diags and all(d.code == "E-SCENARIO" and d.span.file == str(path) for d in diags)
    assert (diags[0].span.line, fragment in diags[0].message) == (line, True), diags[0].render()


def test_aliases_that_do_not_explode_are_fine(tmp_path: Path, names: NameTable) -> None:
    path = write(tmp_path, """
        cycles: 10
        initial: &start {I_key_M3: 1}
        events:
          - {cycle: 2, set: *start}
          - {cycle: 4, set: *start}
        """)
    scenario = load_scenario(path, names)
    assert [e.set for e in scenario.events] == [{"I_key_M3": 1}] * 2


def test_the_cycle_limit_is_inclusive(tmp_path: Path, names: NameTable) -> None:
    assert load_scenario(write(tmp_path, f"cycles: {MAX_CYCLES}\n"), names).cycles == MAX_CYCLES


@pytest.mark.parametrize("text", ["cycles: 5\nsemantics: " + "[" * 20_000 + "]" * 20_000 + "\n",
                                  "cycles: 5\nsemantics: &s {byte_order: [*s]}\n",
                                  "cycles: 5\n" + _alias_bomb(9) + "semantics: {byte_order: *lol8}\n"])
def test_the_settings_read_before_compiling_are_bounded_too(tmp_path: Path, text: str) -> None:
    """The profile and semantics keys are read before the project is compiled (scenario_settings): the same bounds."""
    from transpiler.verify.simulate import scenario_settings
    started = time.perf_counter()
    assert scenario_settings(write(tmp_path, text)) == (None, {}, None)
    assert time.perf_counter() - started < 5
