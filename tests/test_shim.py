"""Tests of the C runtime shim through its ctypes wrapper (transpiler/shim.py), plus the C unit tests."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from decimal import Decimal
from pathlib import Path

import pytest

from transpiler.exec.compiled import shim

ROOT = Path(__file__).resolve().parent.parent
MODULE_CATALOGUE = ROOT / "tests" / "data" / "instructions" / "modules.txt"   # spec 14.2, copied once


class Plc:
    """A toy PLC memory that applies the shim's writes (W and D kept apart by address)."""

    def __init__(self) -> None:
        self.mem: dict[tuple[str, int], int] = {}

    def __getitem__(self, operand: str) -> int:
        return self.mem.get((operand[0], int(operand[1:])), 0)

    def __setitem__(self, operand: str, value: int) -> None:
        self.mem[(operand[0], int(operand[1:]))] = value

    def read_bit(self, marker: int) -> int:
        return self.mem.get(("M", marker), 0)

    def apply(self, writes: list[shim.Write]) -> None:
        for kind, addr, value in writes:
            self.mem[(kind, addr)] = value

    def nc_phase(self, nc: shim.NcModel, cycle: int) -> list[shim.Write]:
        writes = nc.phase(cycle, self.read_bit)
        self.apply(writes)
        return writes


def echo(plc: Plc, strobe: str, ack: str) -> None:
    """A PLC that acknowledges in the cycle it sees the strobe and resets the ack with it."""
    plc[ack] = plc[strobe]


@pytest.fixture()
def nc() -> shim.NcModel:
    with shim.NcModel(20, "itnc530") as model:
        yield model


# --------------------------------------------------------------------------- C unit tests


def test_c_unit_tests_pass() -> None:
    proc = subprocess.run(["make", "-s", "-C", str(ROOT / "runtime_shim"), "test"],
                          capture_output=True, text=True, timeout=300)
    lines = proc.stdout.strip().splitlines()
    assert lines, proc.stderr
    summary = re.fullmatch(r"(\d+) passed, (\d+) failed", lines[-1])
    assert summary, proc.stdout + proc.stderr
    assert summary.group(2) == "0", proc.stderr
    assert int(summary.group(1)) >= 20
    assert proc.returncode == 0


def test_shim_sources_compile_without_warnings(tmp_path: Path) -> None:
    src = ROOT / "runtime_shim"
    proc = subprocess.run(
        ["gcc", "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2", "-fwrapv", "-fPIC", "-shared",
         "-o", str(tmp_path / "lib.so"), str(src / "hh_nc.c"), str(src / "hh_modules.c")],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr


# --------------------------------------------------------------------------- NC model


def test_tv56_m_function_handshake(nc: shim.NcModel) -> None:
    plc = Plc()
    nc.enqueue({"m_function": 3})
    trace: dict[str, list[int]] = {"M4072": [], "M4092": [], "O5": [], "W260": []}
    for cycle in range(3):
        plc.nc_phase(nc, cycle)
        if plc["M4072"] and plc["W260"] == 3:  # the program of TV-56
            plc["O5"] = 1
        echo(plc, "M4072", "M4092")
        for name in trace:
            trace[name].append(plc[name])
    assert trace == {"M4072": [1, 0, 0], "M4092": [1, 0, 0], "O5": [1, 1, 1], "W260": [3, 3, 3]}
    assert nc.pending == 0 and nc.state == "IDLE"


def test_tv58_tool_call_trace(nc: shim.NcModel) -> None:
    plc = Plc()
    nc.enqueue({"tool_call": {"tool": 5, "pocket": 2}})
    trace: dict[str, list[int]] = {"M30": [], "W100": [], "M4093": [], "M4073": [], "W262": []}
    for cycle in range(2):
        plc.nc_phase(nc, cycle)
        plc["M30"] = plc["M4073"] and plc["M4522"]
        if plc["M4073"]:
            plc["W100"] = plc["W264"]
        echo(plc, "M4073", "M4093")
        for name in trace:
            trace[name].append(plc[name])
    assert trace == {"M30": [1, 0], "W100": [5, 5], "M4093": [1, 0], "M4073": [1, 0], "W262": [2, 2]}


def test_first_cycle_marker_and_mode_word(nc: shim.NcModel) -> None:
    plc = Plc()
    assert sorted(plc.nc_phase(nc, 0)) == [("M", 4172, 1), ("W", 272, 1)]
    assert plc.nc_phase(nc, 1) == [("M", 4172, 0)]
    assert plc.nc_phase(nc, 2) == []


def test_first_cycle_marker_setting_moves_the_pulse() -> None:
    plc = Plc()
    with shim.NcModel(20, "itnc530", first_cycle_marker=4171) as model:
        assert sorted(plc.nc_phase(model, 0)) == [("M", 4171, 1), ("W", 272, 1)]
        assert plc.nc_phase(model, 1) == [("M", 4171, 0)]
    with pytest.raises(ValueError, match="first_cycle_marker"):
        shim.NcModel(20, "itnc530", first_cycle_marker=-1)


def test_tnc407_has_no_first_cycle_marker_and_its_own_m_strobe() -> None:
    plc = Plc()
    with shim.NcModel(20, "tnc407") as model:
        model.enqueue({"m_function": 9})
        assert sorted(plc.nc_phase(model, 0)) == [("M", 2045, 1), ("W", 260, 9)]
        for action in ({"tool_call": {"tool": 1, "pocket": 1}}, {"mode": 3}, {"restart": "program"}):
            with pytest.raises(shim.NcActionError, match="not supported by profile tnc407"):
                model.enqueue(action)
        assert model.pending == 1


def test_actions_play_one_at_a_time(nc: shim.NcModel) -> None:
    plc = Plc()
    nc.enqueue({"m_function": 3})
    nc.enqueue({"spindle_speed": 1500})
    nc.enqueue({"fn19": {"value1": 7, "value2": -8}})
    strobes = []
    for cycle in range(8):
        plc.nc_phase(nc, cycle)
        strobes.append((plc["M4072"], plc["M4071"], plc["M4075"]))
        for strobe, ack in (("M4072", "M4092"), ("M4071", "M4091"), ("M4075", "M4095")):
            echo(plc, strobe, ack)
        if cycle == 1:
            assert plc["D356"] == 0  # the S code is written only when its handshake starts
    assert strobes == [(1, 0, 0), (0, 0, 0), (0, 1, 0), (0, 0, 0), (0, 0, 1), (0, 0, 0), (0, 0, 0), (0, 0, 0)]
    assert (plc["D356"], plc["D280"], plc["D284"]) == (1500, 7, -8)
    assert nc.pending == 0


@pytest.mark.parametrize("tool, pocket, marker",
                         [(0, 5, 4521), (5, 1, 4522), (5, 2, 4522), (5, -1, 4523), (5, 0, 4523)])
def test_tool_call_sets_exactly_one_marker(nc: shim.NcModel, tool: int, pocket: int, marker: int) -> None:
    plc = Plc()
    for m in (4521, 4522, 4523):
        plc[f"M{m}"] = 1
    nc.enqueue({"tool_call": {"tool": tool, "pocket": pocket, "second_strobe": False}})
    plc.nc_phase(nc, 0)
    assert {m: plc[f"M{m}"] for m in (4521, 4522, 4523)} == {m: int(m == marker) for m in (4521, 4522, 4523)}
    assert (plc["W264"], plc["W262"], plc["M4073"]) == (tool, pocket, 1)


def test_tool_call_second_strobe(nc: shim.NcModel) -> None:
    plc = Plc()
    nc.enqueue({"tool_call": {"tool": 7, "pocket": 3, "second_strobe": True}})
    trace = []
    for cycle in range(6):
        plc.nc_phase(nc, cycle)
        trace.append((plc["M4073"], plc["M4520"]))
        plc["M4093"] = plc["M4073"] | plc["M4520"]
    assert trace == [(1, 0), (0, 0), (0, 1), (0, 0), (0, 0), (0, 0)]
    assert nc.pending == 0


def test_mode_and_restart(nc: shim.NcModel) -> None:
    plc = Plc()
    nc.enqueue({"mode": 5})
    assert ("W", 272, 5) in plc.nc_phase(nc, 0)
    assert [w for w in plc.nc_phase(nc, 1) if w[1] == 272] == []
    nc.enqueue({"restart": "program"})
    nc.enqueue({"restart": "machine_parameters"})
    levels = []
    for cycle in range(2, 5):
        plc.nc_phase(nc, cycle)
        levels.append((plc["M4173"], plc["M4174"]))
    assert levels == [(1, 1), (0, 0), (0, 0)]


@pytest.mark.parametrize("cycle_time, start, expected", [(20, 0, 501), (20, 4, 505), (30, 0, 334)])
def test_handshake_timeout(cycle_time: int, start: int, expected: int) -> None:
    plc = Plc()
    with shim.NcModel(cycle_time, 0) as model:
        for cycle in range(expected):
            if cycle == start:
                model.enqueue({"gear": 2})
            plc.nc_phase(model, cycle)
        assert model.error is None
        with pytest.raises(shim.HandshakeTimeout) as info:
            plc.nc_phase(model, expected)
        err = info.value
        assert (err.cycle, err.function, err.started, err.strobe, err.ack) == (expected, "gear", start, 4070, 4090)
        assert err.code == "E-SIM-HANDSHAKE-TIMEOUT" and str(expected) in str(err)
        with pytest.raises(shim.HandshakeTimeout):  # sticky
            plc.nc_phase(model, expected + 1)
        assert model.error is not None and model.error.cycle == expected


def test_phase_cycles_must_be_consecutive(nc: shim.NcModel) -> None:
    plc = Plc()
    with pytest.raises(ValueError, match="expected 0"):
        plc.nc_phase(nc, 1)
    plc.nc_phase(nc, 0)
    with pytest.raises(ValueError, match="expected 1"):
        plc.nc_phase(nc, 0)


def test_read_bit_exception_propagates(nc: shim.NcModel) -> None:
    def broken(marker: int) -> int:
        raise KeyError(marker)

    nc.enqueue({"m_function": 1})
    with pytest.raises(KeyError) as info:
        nc.phase(0, broken)
    assert info.value.args == (4092,)


@pytest.mark.parametrize("action, message", [
    ({"m_function": 3, "gear": 1}, "exactly one key"),
    ({"spindle": 1}, "unknown nc action"),
    ({"m_function": True}, "must be an integer"),
    ({"m_function": "3"}, "must be an integer"),
    ({"m_function": 40000}, "16-bit"),
    ({"spindle_speed": 2**31}, "32-bit"),
    ({"tool_call": {"tool": 1}}, "missing key"),
    ({"tool_call": {"tool": 1, "pocket": 1, "slot": 2}}, "unknown key"),
    ({"tool_call": {"tool": 1, "pocket": 1, "second_strobe": 1}}, "true or false"),
    ({"tool_def": 5}, "expects a mapping"),
    ({"fn19": {"value1": 1}}, "missing key"),
    ({"restart": "plc"}, "program or machine_parameters"),
])
def test_invalid_actions_are_rejected(nc: shim.NcModel, action: dict, message: str) -> None:
    with pytest.raises(shim.NcActionError, match=message):
        nc.enqueue(action)
    assert nc.pending == 0


def test_unknown_profile() -> None:
    with pytest.raises(ValueError, match="unknown profile"):
        shim.NcModel(20, "tnc640")
    with pytest.raises(ValueError):
        shim.NcModel(0, 0)


# --------------------------------------------------------------------------- modules


@pytest.fixture()
def sysm() -> shim.SysModules:
    with shim.SysModules(20) as context:
        yield context


@pytest.mark.parametrize("number, kind, nparams, nresults", [
    (9006, "modelled", 1, 0), (9031, "modelled", 3, 1), (9032, "modelled", 2, 1), (9035, "modelled", 1, 1),
    (9036, "modelled", 2, 1), (9192, "modelled", 1, 1), (9195, "modelled", 0, 1), (9041, "stub", 2, 0),
    (9094, "modelled", 4, 1), (9097, "modelled", 2, 1), (9081, "stub", 0, 1), (9051, "stub", 5, 0), (9999, "unknown", 0, 0),
])
def test_module_info(sysm: shim.SysModules, number: int, kind: str, nparams: int, nresults: int) -> None:
    info = sysm.info(number)
    assert (info.kind, info.nparams, info.nresults) == (kind, nparams, nresults)
    assert info == shim.module_info(number)


def test_module_table_covers_the_spec_catalogue() -> None:
    lines = [line.split()[0] for line in MODULE_CATALOGUE.read_text(encoding="utf-8").splitlines()
             if line.strip() and not line.startswith("#")]
    numbers = {int(n) for n in lines}
    assert len(numbers) == len(lines) == 27, "tests/data/instructions/modules.txt lists the 27 modules of spec 14.2"
    table = {info.number: info for info in shim.module_table()}
    assert numbers <= set(table)
    assert all(info.known for info in table.values())


def test_unknown_module_and_wrong_parameter_count(sysm: shim.SysModules) -> None:
    with pytest.raises(shim.UnknownModule):
        sysm.call(9999, [])
    with pytest.raises(ValueError, match="takes 1 parameter"):
        sysm.call(9192, [])


def test_stub_module_pushes_zeros(sysm: shim.SysModules) -> None:
    assert sysm.call(9081, []) == ([0], 0, None)


def test_9006_needs_numbermp4111(sysm: shim.SysModules) -> None:
    assert sysm.call(9006, [96]) == ([], 1, 1)
    assert sysm.service() == []
    sysm.set_number_mp4111(3)
    assert sysm.call(9006, [98]) == ([], 0, None)
    assert sysm.call(9006, [99]) == ([], 1, 1)
    with pytest.raises(ValueError):
        sysm.set_number_mp4111(905)


@pytest.mark.parametrize("value, cycle_time, unit, cycles", [
    ("0.125", 20, "seconds", 7), (0.1, 20, "seconds", 5), (2, 20, "seconds", 100),
    (Decimal("0.1"), 30, "seconds", 4), (3, 20, "cycles", 3), (0, 20, "seconds", 0),
])
def test_9006_timer_runs_for_its_preset(value, cycle_time: int, unit: str, cycles: int) -> None:
    with shim.SysModules(cycle_time, number_mp4111=1, timer_unit=unit) as context:
        context.set_mp(4111, 96, value)
        context.service()
        assert context.call(9006, [96]) == ([], 0, None)  # started in cycle 0
        running = []
        for _ in range(cycles + 3):
            context.tick()
            (write,) = context.service()
            assert write[:2] == ("T", 96) and write[2] == context.timer_running(96)
            running.append(write[2])
        assert running == [1] * cycles + [0] * 3


def test_mp_read_write_9031_9032(sysm: shim.SysModules) -> None:
    sysm.set_mp(4110, 3, "0.50")
    assert sysm.get_mp(4110, 3) == Decimal("0.50")
    assert sysm.call(9032, [4110, 3]) == ([50], 0, None)
    assert sysm.call(9031, [4110, 3, 75]) == ([0], 0, None)
    assert sysm.get_mp(4110, 3) == Decimal("0.75")
    assert sysm.call(9031, [4110, 9, 1]) == ([1], 1, 1)
    assert sysm.call(9032, [4110, 9]) == ([0], 1, 1)
    assert sysm.get_mp(4110, 9) is None
    sysm.set_mp(4110, 4, "0.5000000000")
    assert sysm.get_mp(4110, 4) == Decimal("0.5")
    for bad in ("x", float("nan"), True, "1e-12"):
        with pytest.raises(ValueError):
            sysm.set_mp(1, 0, bad)


def test_status_table_9035_9036(sysm: shim.SysModules) -> None:
    assert sysm.call(9036, [10, -5]) == ([0], 0, None)      # 10: the jog-increment limit, any value
    assert sysm.call(9035, [10]) == ([-5], 0, None)
    sysm.set_status(13, 4)
    assert sysm.call(9035, [13]) == ([4], 0, None)
    assert sysm.call(9036, [256, 1]) == ([1], 1, 2)          # wrong number: result 1, W1022 2
    with pytest.raises(ValueError):
        sysm.set_status(-1, 0)


def test_clock_9192_9195() -> None:
    with shim.SysModules(40) as context:
        for _ in range(74):
            context.tick()
        assert (context.cycle, context.time_ms) == (74, 2960)
        assert [context.call(9192, [n])[0] for n in (-3, -2, -1, 8)] == [[2], [2], [2], [-1]]
        context.tick()
        assert context.call(9195, []) == ([3], 0, None)


def test_module_result_override(sysm: shim.SysModules) -> None:
    sysm.set_module_results(9192, [3600])
    assert sysm.call(9192, [-1]) == ([3600], 0, None)
    sysm.set_module_results(9192, [])
    assert sysm.call(9192, [-1]) == ([0], 0, None)
    with pytest.raises(ValueError, match="1 result"):
        sysm.set_module_result(9192, 1, 5)
    with pytest.raises(shim.UnknownModule):
        sysm.set_module_result(9999, 0, 5)


# --------------------------------------------------------------------------- building and loading


def _copy_sources(tmp_path: Path) -> Path:
    root = tmp_path / "runtime_shim"
    root.mkdir()
    for path in (ROOT / "runtime_shim").iterdir():
        if path.is_file():
            shutil.copy2(path, root / path.name)
    return root


def test_load_shim_builds_a_missing_library_and_rebuilds_a_stale_one(tmp_path: Path) -> None:
    root = _copy_sources(tmp_path)
    lib = shim.ensure_built(root)
    assert lib == root / "build" / shim.LIB_NAME and lib.exists()
    assert shim.load_shim(root).hh_module_count() == len(shim.module_table())
    before = lib.stat().st_mtime_ns
    assert shim.ensure_built(root).stat().st_mtime_ns == before  # fresh: not rebuilt
    future = time.time() + 5
    os.utime(root / "hh_nc.h", (future, future))
    shim.ensure_built(root)
    assert lib.stat().st_mtime_ns > before


def test_build_failure_is_shim_unavailable_with_gcc_message(tmp_path: Path) -> None:
    root = _copy_sources(tmp_path)
    with open(root / "hh_modules.c", "a", encoding="utf-8") as f:
        f.write("\n#error deliberately broken for the test\n")
    with pytest.raises(shim.ShimUnavailable, match="deliberately broken"):
        shim.load_shim(root)


def test_missing_compiler_is_shim_unavailable_naming_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    root = _copy_sources(tmp_path)
    monkeypatch.setenv("PATH", str(tmp_path / "no-such-dir"))
    monkeypatch.delenv("CC", raising=False)
    with pytest.raises(shim.ShimUnavailable, match="no C compiler found .*'cc' and 'gcc'"):
        shim.ensure_built(root)
