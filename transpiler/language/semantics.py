"""Control profiles and the single table of semantic choices (every ASSUMPTION; docs/assumptions.md lists them)."""

from __future__ import annotations

import dataclasses
from typing import Any, Mapping


@dataclasses.dataclass(frozen=True)
class Assumption:
    """One documented, switchable semantic choice."""

    id: str
    key: str
    default: Any
    alternatives: tuple[Any, ...]
    topic: str
    vectors: tuple[str, ...] = ()
    # A choice of how the ST is written, not of what the control does: nothing to confirm on the machine.
    layout_only: bool = False


# The one place where every ASSUMPTION lives. `key` is the config key (`-S key=value`,
# scenario `semantics:`); profile-specific defaults are in PROFILES below.
ASSUMPTIONS: tuple[Assumption, ...] = (
    Assumption("A-01", "symbol_case", "sensitive", ("insensitive",), "case of symbols and labels", ("TV-65",)),
    Assumption("A-02", "star_comments", True, (False,), "'*' comment lines in .src/.cfg"),
    Assumption("A-02b", "lenient_brackets", True, (False,), "blank between mnemonic and '['"),
    Assumption("A-03", "chain_model", "static", ("dynamic",), "static chain state (OPENER/CLOSER/NEUTRAL)",
               ("TV-03", "TV-04", "TV-05", "TV-06", "TV-14", "TV-39", "TV-84")),
    Assumption("A-04", "bracket_at_chain_start", "load", ("gate",), "logic bracket at chain start", ("TV-14",)),
    Assumption("A-05", "accumulator_model", "separate", ("shared_bit7",), "LA and WA registers", ("TV-69",)),
    Assumption("A-06", "load_extension", "sign", ("zero",), "word load of B/W", ("TV-15", "TV-21")),
    Assumption("A-07", "ln_word", "sign_extended", ("operand_width",), "LN with a word operand", ("TV-80",)),
    Assumption("A-08", "store_truncation", "truncate", ("saturate",), "word store of B/W", ("TV-18",)),
    Assumption("A-09", "add_overflow", "wrap", ("flag",), "+/- overflow", ("TV-22",)),
    Assumption("A-10", "mul_overflow_result", "low_bits", ("unchanged",), "x result on overflow", ("TV-23",)),
    Assumption("A-11", "div_semantics", "trunc", ("floor",), "/ and MOD rounding; division by zero", ("TV-24", "TV-25")),
    Assumption("A-12", "div_min_by_minus_one", "no_flag", ("flag",), "-2^31 / -1"),
    Assumption("A-13", "compare_signedness", "signed", ("unsigned",), "comparison signedness", ("TV-26", "TV-27", "TV-57", "TV-78")),
    Assumption("A-14", "shift_semantics", "mod32", ("fault",), "shift count and overflow", ("TV-32",)),
    Assumption("A-16", "allow_assign_not", False, (True,), "=N instruction"),
    Assumption("A-17", "index_register_width", 32, (16,), "width of X as word operand"),
    Assumption("A-18", "bracket_width", 32, ("operand",), "width of logic-word and compare bracket results", ("TV-31",)),
    Assumption("A-19", "data_stack_words", 256, (), "data stack capacity in 16-bit words", ("TV-36", "TV-37", "TV-60")),
    Assumption("A-20", "psx_width", 32, (16,), "PSX/PLX width"),
    Assumption("A-21", "index_scaling", "bytes", ("elements",), "index scaling of W/D", ("TV-61",)),
    Assumption("A-22", "index_read_check", True, (False,), "range check of indexed reads", ("TV-62",)),
    Assumption("A-23", "extended_instructions", True, (False,), "INC/DEC/INCW/DECW/INCX/DECX/NOTL/NOTW/TWOC"),
    Assumption("A-24", "case_out_of_range", "skip", ("fault",), "CASE selector out of range", ("TV-42", "TV-43", "TV-44")),
    Assumption("A-26", "while_retest", "keyword", ("chain",), "WHILE re-test", ("TV-46",)),
    Assumption("A-29", "call_depth", 32, (), "maximum call depth", ("TV-60", "TV-67")),
    Assumption("A-32", "cycle_phases", "nc_inputs_timers_main", ("timers_after_main",), "cycle phase order", ("TV-50", "TV-51", "TV-52", "TV-54")),
    Assumption("A-34a", "timer_start_consumed", True, (False,), "timer start operand consumed by the service", ("TV-50",)),
    Assumption("A-34b", "timer_restart_while_running", True, (False,), "a start restarts a running timer", ("TV-51",)),
    Assumption("A-35", "timer_unit", "seconds", ("cycles",), "unit of MP4110/MP4111 presets"),
    Assumption("A-36a", "counter_start_consumed", True, (False,), "counter start operand consumed", ("TV-54",)),
    Assumption("A-36b", "counter_counts", "cycles", ("rising_edges",), "counter counts released cycles or release edges", ("TV-68",)),
    Assumption("A-38", "first_cycle_marker", 4172, (), "first-cycle marker", ("TV-59",)),
    Assumption("A-42", "byte_order", "little", ("big",), "byte order of W/D", ("TV-16", "TV-17")),
    Assumption("A-44", "nonvolatile", "", (), "non-volatile operand ranges (e.g. 'M1000-2000,B0-127')"),
    Assumption("A-45", "submit_model", "same_cycle", ("next_cycle",), "submit-job scheduling", ("TV-73",)),
    Assumption("A-46q", "module_context", "enforce", ("ignore",), "calling context of PLC modules: a submit-only "
               "module in the cyclic program fails with W1022 = 20, a cyclic-only one in a job with 24"),
    Assumption("A-51", "word_gate_at_chain_start", "gate", ("load",), "word gating at chain start", ("TV-70",)),
    Assumption("A-56", "literal_range", "bit_pattern", ("documented",), "literal range", ("TV-19",)),
    Assumption("A-57a", "cycle_time_ms", 20, (), "PLC cycle time"),
    Assumption("A-57b", "max_instructions_per_cycle", 1_000_000, (), "watchdog instruction budget"),
    Assumption("A-59", "bracket_span", "forbidden", ("allowed",), "control flow inside brackets"),
    Assumption("A-37", "number_mp4111", 0, (), "NUMBERMP4111 of OEM.SYS: how many additional timers T96... module 9006 "
               "may start (the project sets it with DEFINE NUMBERMP4111 = n in its configuration)"),
    Assumption("A-61", "define_case", "insensitive", ("sensitive",), "case of DEFINE names (E-PP-CASE on a differing "
               "spelling)"),
    Assumption("A-62", "marker_structs", True, (False,), "markers sharing a symbol prefix (ML_ax_*) as one STRUCT "
               "(how the ST is written, not what the control does)", layout_only=True),
    Assumption("A-63", "mask_d_format", "signed", ("d_unsigned",), "screen masks: %d and %D both show the operand's "
               "signed value (d_unsigned: %d shows it unsigned within the operand's width, %D stays signed)"),
    Assumption("A-64", "mask_c_modifier", "printf", ("clip",), "screen masks: the undocumented /c modifier changes "
               "nothing, a value wider than its field widens the line as printf does (clip: /c fills such a field "
               "with '*')"),
)

ASSUMPTION_BY_KEY: dict[str, Assumption] = {a.key: a for a in ASSUMPTIONS}


@dataclasses.dataclass(frozen=True)
class Ranges:
    """Operand address ranges of a profile: a tuple of inclusive (lo, hi) intervals per kind."""

    M: tuple[tuple[int, int], ...]
    I: tuple[tuple[int, int], ...]
    O: tuple[tuple[int, int], ...]
    T: tuple[tuple[int, int], ...]
    C: tuple[tuple[int, int], ...]
    B: tuple[tuple[int, int], ...]   # byte memory (B/W/D share it)
    S: tuple[tuple[int, int], ...]

    def contains(self, kind: str, addr: int) -> bool:
        return any(lo <= addr <= hi for lo, hi in getattr(self, kind))

    def size(self, kind: str) -> int:
        return max(hi for _, hi in getattr(self, kind)) + 1


@dataclasses.dataclass(frozen=True)
class Interface:
    """NC interface operands of a profile (strobes, acknowledgements, error and first-cycle markers)."""

    mul_err: int
    div_err: int
    mod_err: int
    module_err: int
    module_err_code_word: int | None
    first_cycle: int | None
    program_restart: int | None
    mp_restart: int | None
    interface_markers: frozenset[int]
    interface_bytes: frozenset[int]   # byte addresses of interface W/D operands
    error_markers: tuple[int, int]


_ITNC_IF_MARKERS = frozenset(
    list(range(4070, 4076)) + list(range(4090, 4096)) + [4120, 4121, 4122, 4123, 4130, 4131, 4132, 4134, 4135]
    + [4172, 4173, 4174] + list(range(4200, 4204)) + list(range(4520, 4524)) + list(range(4538, 4544))
)
_ITNC_IF_BYTES = frozenset(
    list(range(256, 258)) + list(range(260, 266)) + list(range(272, 274)) + list(range(280, 288))
    + list(range(356, 360)) + list(range(516, 518)) + list(range(528, 532)) + list(range(544, 548))
    + list(range(1022, 1028)) + list(range(1032, 1034))
)


@dataclasses.dataclass(frozen=True)
class Profile:
    """A control generation: ranges, byte order, interface operands and assumption defaults."""

    name: str
    ranges: Ranges
    interface: Interface
    timer_start: tuple[int, int]
    timer_running: tuple[int, int]
    counter_start: tuple[int, int]
    counter_running: tuple[int, int]
    counter_release: tuple[int, int]
    string_len: int
    defaults: Mapping[str, Any]

    def is_interface(self, kind: str, addr: int, width: int = 1) -> bool:
        if kind == "M":
            return addr in self.interface.interface_markers or (
                self.interface.error_markers[0] <= addr <= self.interface.error_markers[1])
        if kind in "BWD":
            return all(a in self.interface.interface_bytes for a in range(addr, addr + width))
        return False


_TNC426_RANGES = Ranges(M=((0, 4999),), I=((0, 383),), O=((0, 191),), T=((0, 303),), C=((0, 143),),
                        B=((0, 4095),), S=((0, 15),))
_ITNC_RANGES = Ranges(M=((0, 9999),), I=((0, 4095),), O=((0, 4095),), T=((0, 999),), C=((0, 143),),
                      B=((0, 9999),), S=((0, 99),))
_TNC407_RANGES = Ranges(M=((0, 3023),), I=((0, 31), (64, 126), (128, 152), (192, 254)),
                        O=((0, 30), (32, 62), (64, 94)), T=((0, 95),), C=((0, 31), (48, 79), (96, 127)),
                        B=((0, 1023),), S=((0, 15),))

_ITNC_IF = Interface(4200, 4201, 4202, 4203, 1022, 4172, 4173, 4174, _ITNC_IF_MARKERS, _ITNC_IF_BYTES, (4800, 4999))
_TNC407_IF = Interface(3168, 3169, 3170, 3171, None, None, None, None,
                       frozenset([2045, 2046, 2482, 2496, 3168, 3169, 3170, 3171, 3172]),
                       frozenset(list(range(260, 264)) + list(range(268, 272))), (2924, 3023))


def _defaults(**overrides: Any) -> dict[str, Any]:
    values = {a.key: a.default for a in ASSUMPTIONS}
    values.update(overrides)
    return values


PROFILES: dict[str, Profile] = {
    "itnc530": Profile("itnc530", _ITNC_RANGES, _ITNC_IF, (0, 47), (48, 95), (0, 47), (48, 95), (96, 143), 128,
                       _defaults()),
    "tv": Profile("tv", _ITNC_RANGES, _ITNC_IF, (0, 47), (48, 95), (0, 47), (48, 95), (96, 143), 128,
                  _defaults(timer_unit="cycles")),
    "tnc426": Profile("tnc426", _TNC426_RANGES, _ITNC_IF, (0, 47), (48, 95), (0, 47), (48, 95), (96, 143), 128,
                      _defaults(byte_order="big", timer_unit="cycles")),
    "tnc407": Profile("tnc407", _TNC407_RANGES, _TNC407_IF, (0, 47), (48, 95), (0, 31), (48, 79), (96, 127), 128,
                      _defaults(byte_order="big", timer_unit="cycles", extended_instructions=False,
                                nonvolatile="M1000-2000,B0-127")),
}


class SemanticsError(ValueError):
    pass


@dataclasses.dataclass(frozen=True)
class Semantics:
    """The profile plus the effective value of every semantic choice for one run."""

    profile: Profile
    values: Mapping[str, Any]

    def __getitem__(self, key: str) -> Any:
        return self.values[key]

    @property
    def little_endian(self) -> bool:
        return self.values["byte_order"] == "little"

    def describe(self) -> list[tuple[str, str, Any, bool]]:
        """(id, key, value, is_default) rows for the migration report."""
        rows = []
        for a in ASSUMPTIONS:
            value = self.values[a.key]
            rows.append((a.id, a.key, value, value == self.profile.defaults[a.key]))
        return rows


def _coerce(key: str, raw: Any) -> Any:
    a = ASSUMPTION_BY_KEY[key]
    if isinstance(a.default, bool):
        if isinstance(raw, bool):
            return raw
        text = str(raw).lower()
        if text in ("1", "true", "on", "yes"):
            return True
        if text in ("0", "false", "off", "no"):
            return False
        raise SemanticsError(f"{key} expects true/false, not {raw!r}")
    if isinstance(a.default, int):
        if str(raw) in {str(x) for x in a.alternatives}:
            return str(raw)          # a named alternative of a numeric setting (bracket_width = operand)
        try:
            return int(raw)
        except (TypeError, ValueError):
            raise SemanticsError(f"{key} expects an integer, not {raw!r}") from None
    text = str(raw)
    allowed = {a.default, *a.alternatives}
    if a.alternatives and text not in allowed:
        raise SemanticsError(f"{key} expects one of {', '.join(sorted(map(str, allowed)))}, not {raw!r}")
    return text


def make_semantics(profile_name: str = "itnc530", overrides: Mapping[str, Any] | None = None) -> Semantics:
    """Build the semantics of a run; raises SemanticsError on an unknown profile, key or value."""
    profile = PROFILES.get(profile_name)
    if profile is None:
        raise SemanticsError(f"unknown profile {profile_name!r} (known: {', '.join(PROFILES)})")
    values = dict(profile.defaults)
    for key, raw in (overrides or {}).items():
        if key not in ASSUMPTION_BY_KEY:
            raise SemanticsError(f"unknown semantic setting {key!r}")
        values[key] = _coerce(key, raw)
    return Semantics(profile, values)
