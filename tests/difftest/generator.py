"""Seeded generator of random, well-defined HEIDENHAIN PLC projects ("Csmith for HEIDENHAIN").

A generated project is run on the reference interpreter and, translated to ST, on an ST executor; both are
compared every cycle (`hh2iec equiv`).  Every program is meant to be free of compile errors and of runtime
faults (spec sections 5-13): loops are bounded by counters in reserved words, the index register is masked
into the bounds of its table right before each indexed access, the data stack is balanced, brackets and
structured statements are closed inside their block, subprograms call only subprograms generated before them
(no recursion, bounded depth).  With `faults=True` exactly one runtime fault is injected (behind an input).

Layout of a project: `main.src` (preamble, top-level blocks, the EM of the main program, subprogram and
KFIELD blocks), optional modules `mod1.src`/`mod2.src` (USES/GLOBAL/EXTERN), `defs.def` (global symbols),
`m<n>_local.def` (file-local symbols), `OEM.cfg` (DEFINEs for `#if`), `timers.mp` (MP4110/MP4120 presets)
and `scenario.yaml` (300 cycles of random stimulus on I0..I31 plus a few NC handshakes and restarts, for
`hh2iec equiv main.src --scenario scenario.yaml`).

Every top-level block starts with a line `; @block` and is self-contained: jump labels never cross blocks;
a block depends on other blocks only through calls of subprograms (each in its own block) and reads of a
KFIELD table (in its own block).

Features (names in FEATURES) can be switched off one by one, so that a construct that makes the translator
diverge can be set aside while the rest is tested:  generate(seed, disable={"stack_mixed"}).

Command line:  python -m tests.difftest.generator --seed N [--size K] [--faults] [--enable F,G] [--disable F,G]
               --out DIR    (or --list-features)
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import re
import sys
from pathlib import Path
from types import MappingProxyType
from typing import Callable, Iterable, Mapping

# ---------------------------------------------------------------------------------------------------------
# features

FEATURES: Mapping[str, str] = MappingProxyType({
    "logic": "logic chains L/LN/A/AN/O/ON/XO/XON and =/S/R/SN/RN on I/M/O/T/C, gates at chain start (5.4, 6.1-6.3)",
    "word": "word loads/stores B/W/D/K, L-/LN, overlapping B/W/D, word gating, + - x / MOD with overflow and "
            "division by zero, error markers M4200-M4202, per-cycle accumulation (5.2, 6.1, 6.2, 6.4, 6.5)",
    "compare": "== <> < > <= >= over the operand width (6.6)",
    "shift": "<< >> with any count, BS/BC/BT (6.7, 6.8)",
    "brackets_logic": "logic brackets A[ AN[ O[ ON[ XO[ XON[, nested, load brackets at chain start (6.9)",
    "brackets_word": "arithmetic, comparison and word-logic brackets, nested, /[ MOD[ by zero (6.9, 17b.4)",
    "stack": "PS/PL of bits and values, PSW/PLW, PSL/PLL, PSX/PLX, balanced (6.10)",
    "stack_mixed": "pushes and pulls of different widths on the 16-bit stack, e.g. PS M1 / PS M2 / PL D0 (6.10)",
    "jumps": "forward JP/JPT/JPF, dead code after JP, LA kept across a jump (6.11)",
    "loops": "bounded backward loops with a counter word or X (6.11)",
    "calls": "subprograms LBL/EM, CM/CMT/CMF, EMT/EMF early returns (6.12)",
    "acc_calls": "subprograms that work on the caller's WA or LA (results in registers, 6.12 A-29)",
    "stack_calls": "subprograms with parameters and results on the data stack (6.10, 6.12)",
    "modules": "multi-file projects: USES/GLOBAL/EXTERN, file-local labels and .def files (1.2, 3.3, 3.4)",
    "case": "CASE/ENDC step tables, selectors in and out of range (6.15.1)",
    "case_empty": "CASE tables without entries, written so or emptied by #if (6.15.1, 3.2)",
    "struct": "IFT/IFF/ELSE/ENDI (6.15)",
    "while": "WHILET/WHILEF/ENDW, bounded (6.15)",
    "repeat": "REPEAT/UNTILT/UNTILF, bounded (6.15)",
    "index": "index register X, indexed B/W/D/M/I/O and symbol[X], X as word operand (6.13)",
    "index_wide": "indexed stores to W and D operands, e.g. L W50 / A K12 / = X / L D4[X] / + K1 / = D4[X] (6.13)",
    "kfield": "KFIELD tables and KF name[X] (6.17)",
    "timers": "timer starts T0-T23, running T48-T71, presets MP4110 in seconds (9)",
    "counters": "counter starts C0-C15, running C48-C63, release C96-C111, presets MP4120 (10)",
    "edges": "rising/falling edge idiom with memory markers (11)",
    "nc": "reads of NC interface operands (M4172, W272, W260/W262/W264, strobes, D280) and acknowledgements (12)",
    "cfg": "#if/#else/#endif/#ifdef/#ifndef on DEFINEs of OEM.cfg, also in .def files and CASE tables (3.1, 3.2)",
    "defs": "a .def file with symbolic names, constants, auto-assigned operands and aliases (4.2)",
    "extended": "INC/DEC/INCW/DECW/INCX/DECX/NOTL/NOTW/TWOC (6.14)",
    "bitpack": "LB/LW/LD and B=/W=/D= between bit operands and words (6.1, 6.2)",
    "strings": "string accumulator: L/+/= on S, S\"..\", S#E/S#D, string comparisons (6.16)",
    "strings_long": "string results longer than 128 characters, truncated with a warning (6.16, A-50)",
    "main_em": "EMT/EMF in the main program (ends the cycle early) (6.12)",
    "goto_mix": "jumps that cross: overlapping forward jumps, jumps out of WHILE/REPEAT bodies, a loop's "
                "backward jump inside an IFT (never into a structure)",
    "acc_carry": "a block that continues with the WA/LA left by the block before it (or by the previous cycle)",
    "reg_flow": "WA/LA live across conditional jumps, IFT/ELSE and loops (saved with PSW/PLW), merged afterwards",
    "write_input": "writes to input operands (allowed, overwritten by the next input latch, A-33)",
    "case_mix": "mnemonics in lower case and blanks between operand letter and number (2.3, 2.5)",
    "submit": "submit jobs: job subprograms queued with SUBM (identifier stored), RPLY/CAN of them from the main "
              "program, SUBM (gives 0), RPLY and CAN of the running job inside the job's own subprogram; with "
              "\"calls\" only (6.18, A-45)",
    "plc_modules": "PLC module calls that translate: parameters pushed, CM 9xxx, results pulled, M4203/W1022 read "
                   "(with \"stack\" only); "
                   "pure 9050/9052/9053/9054/9070 and every data and machine module but 9006, in the cyclic program "
                   "and in submit jobs (14, A-46)",
})

# Features disabled by default because the translation cannot match them on the targets; re-enable with
# generate(..., enable={"name"}) to check whether that changed.
KNOWN_DIVERGENT: Mapping[str, str] = MappingProxyType({
    "strings_long": "a target limit, not a translator bug: the ST declares plain STRING (matiec rejects STRING[n]), which "
                    "holds 126 characters in matiec and the built-in executor; a result of 127 or 128 characters is "
                    "cut at 126 (report.md lists it under 'Target limits')",
})


def default_features() -> frozenset[str]:
    return frozenset(FEATURES) - frozenset(KNOWN_DIVERGENT)


# ---------------------------------------------------------------------------------------------------------
# result


@dataclasses.dataclass(frozen=True)
class GeneratedProject:
    seed: int
    files: dict[str, str]      # relative file name -> text
    main: str                  # name of the main .src in files
    cfg: str | None            # the .cfg to pass with --cfg, or None
    mp: str | None             # the MP file (timer/counter presets), or None

    def write(self, root: Path) -> Path:
        root = Path(root)
        root.mkdir(parents=True, exist_ok=True)
        for name in sorted(self.files):
            (root / name).write_text(self.files[name], encoding="ascii", newline="\n")
        return root / self.main


# ---------------------------------------------------------------------------------------------------------
# memory map (itnc530 profile).  General pools are shared by all blocks so that values flow between them;
# the reserved areas belong to one block or one subprogram each.

BYTES_PER_OPERAND: Mapping[str, int] = MappingProxyType({"B": 1, "W": 2, "D": 4})
GEN_BYTES = 128          # B0..B127: general B/W/D pool (hot part: the first 64 bytes)
IDX_BYTE_MAX = 100       # base of an indexed byte/word/double table: below 100 (+ at most 15)
M_GEN = 128              # M0..M127 general markers
O_GEN = 48               # O0..O47 general outputs (O48..O63 indexed output tables)
N_INPUTS = 32            # I0..I31
M_TABLE = 300            # M300..M395: indexed marker tables
LOOP_WORDS = 2000        # W2000, W2002, ...: loop counters and bounds (one per loop)
SUB_DOUBLES = 4000       # D4000, D4004, ...: parameters and results of stack subprograms
M_EDGE = 1000            # M1000...: edge memories and edge results (one per edge)
M_SUBPAR = 3000          # M3000...: bit parameters of stack subprograms
N_TIMERS = 24           # timer starts T0..T23
TIMER_RUNNING = 48      # T48+n: timer n is running
TIMER_PRESETS = ("0.02", "0.04", "0.05", "0.06", "0.1", "0.125", "0.2", "0.3", "0", "0.01", "0.5")  # MP4110, s
N_COUNTERS = 16         # counter starts C0..C15
COUNTER_RUNNING = 48    # C48+n: counter n is running
COUNTER_RELEASE = 96    # C96+n: counter n counts while this is 1
COUNTER_PRESETS = (0, 1, 2, 3, 4, 5, 7, 10, 20)                                                    # MP4120, cycles
N_STRINGS = 10

GATES = ("A", "AN", "O", "ON", "XO", "XON")
ARITH = ("+", "-", "x", "/", "MOD")
COMPARES = ("==", "<>", "<", ">", "<=", ">=")
ASSIGNS = ("=", "S", "R", "SN", "RN")
ASSIGN_WEIGHTS = (6, 2, 2, 1, 1)

IF_READ_BITS = (4172, 4173, 4174, 4200, 4201, 4202, 4203, 4070, 4071, 4072, 4073, 4074, 4075, 4520, 4521, 4522, 4523)
IF_READ_WORDS = ("W272", "W260", "W262", "W264", "W256", "D280", "D284", "D356", "W1022")
ARITH_ERROR_MARKERS = (4200, 4201, 4202)   # x overflow, / by zero, MOD not executed (13)
ACKS = ((4070, 4090), (4071, 4091), (4072, 4092), (4073, 4093), (4074, 4094), (4075, 4095))
# overflow, sign of / and MOD, shifts into and out of the sign bit, division by zero (6.5, 6.7)
ARITH_EDGE_CASES = (("K-2147483648", "/", "K-1"), ("K-2147483648", "MOD", "K-1"), ("K65536", "x", "K65536"),
                    ("K-2147483648", "x", "K-1"), ("K2147483647", "+", "K1"), ("K-2147483648", "-", "K1"),
                    ("K-7", "/", "K2"), ("K-7", "MOD", "K2"), ("K7", "MOD", "K-2"), ("K-1", ">>", "K31"),
                    ("K1", "<<", "K31"), ("K46341", "x", "K46341"), ("K-2147483648", "/", "K0"),
                    ("K-32768", "x", "K-65536"))
EDGE_CONSTS = (0, 1, -1, 2, 3, 7, 8, 15, 16, 31, 32, 100, 127, 128, 255, 256, -128, -129, 32767, 32768, -32768,
               -32769, 65535, 65536, 2147483647, -2147483647, -2147483648)


# PLC modules the generator calls (the itnc530 profile's modules that translate, see
# transpiler/backends/st/modcalls.py), with a kind for each parameter in push order and the number of results:
#   any: any value; small: -1..12; mask: a bit mask; hour: -4..8 (9190-9192); addr: a byte address;
#   str: a string number (0..9, sometimes invalid); status: a status number (9035/9036); axis/info (9038/9048/9049)
# 9031/9032 take (number, index) of a machine parameter of timers.mp; 9019 and 9006 do not translate.
PURE_MODULES: Mapping[int, tuple[tuple[str, ...], int]] = MappingProxyType({
    9050: (("any", "exp", "str"), 0), 9052: (("str",), 2), 9053: (("addr", "str", "count"), 0),
    9054: (("str", "addr"), 0), 9070: (("str", "str"), 1), 9019: ((), 1),
})
SYS_MODULES: Mapping[int, tuple[tuple[str, ...], int]] = MappingProxyType({
    9031: (("mp", "mpindex", "any"), 1), 9032: (("mp", "mpindex"), 1), 9035: (("status",), 1),
    9036: (("status", "any"), 1), 9038: (("axis", "info"), 1), 9040: (("addr", "small"), 0),
    9041: (("addr", "small"), 0), 9042: (("addr",), 0), 9048: (("axis", "info"), 1), 9049: (("axis", "info"), 1),
    9092: (("small", "small", "any"), 2), 9093: (("small", "small", "small"), 2),
    9094: (("small", "small", "small", "any"), 1), 9095: (("small",), 1), 9097: (("small", "small"), 1),
    9101: (("small",), 0), 9102: (("small",), 1), 9105: (("small", "addr", "small"), 0),
    9106: (("small", "addr"), 1), 9123: (("axis", "any", "small"), 1), 9124: (("axis", "any"), 1),
    9127: (("axis", "small"), 1), 9144: (("small", "small", "small"), 1), 9148: ((), 0),
    9150: (("small", "addr"), 1), 9159: ((), 1), 9161: (("mask",), 0), 9162: ((), 1), 9166: ((), 0),
    9169: (("mask",), 0), 9190: (("hour",), 0), 9191: (("hour",), 0), 9192: (("hour",), 1),
    9194: (("hour", "any", "small"), 0), 9195: ((), 1), 9221: (("axis", "any", "any"), 0), 9222: (("axis",), 1),
    9227: (("axis", "any", "any", "any", "any", "small"), 0), 9231: (("axis", "any"), 0),
    9244: (("small", "str"), 1), 9260: (("small", "small", "mask"), 1), 9261: (("small", "mask"), 0),
    9262: ((), 0), 9263: (("small",), 0), 9264: (("small", "mask"), 0),
    9429: (("small", "str", "small"), 4),
})
# modules valid only in a submit job (called in the cyclic program they fail with code 20): jobs prefer them
SUBMIT_ONLY_MODULES = (9031, 9032, 9035, 9092, 9093, 9094, 9095, 9097, 9105, 9106, 9192, 9194, 9244, 9260, 9262,
                       9263, 9264)
MAIN_RANK = 10 ** 6      # rank of the main program's context: every subprogram is callable


@dataclasses.dataclass
class _Sub:
    name: str
    unit: "_Unit"
    kind: str                  # plain | wa | la | stack | bitstack
    rank: int
    params: int = 0
    cost: int = 1
    calls: int = 0
    exported: bool = False
    lines: list[str] = dataclasses.field(default_factory=list)
    ident: str = ""            # a submit job: the word that holds its identifier (stored by the main program)


class _Unit:
    """One .src file being generated."""

    def __init__(self, name: str, is_main: bool, stem: str):
        self.name = name
        self.is_main = is_main
        self.stem = stem
        self.names_made = 0         # numbers the labels and tables of this file
        self.subs: list[_Sub] = []
        self.kfields: list[tuple[str, list[str]]] = []
        self.uses: list[_Unit] = []
        self.local_syms: dict[tuple[str, int], str] = {}
        self.local_def_lines: list[str] = []

    def fresh(self, stem: str) -> str:
        self.names_made += 1
        return f"{stem}{self.names_made}"


@dataclasses.dataclass(frozen=True)
class _Ctx:
    unit: _Unit
    rank: int                  # callable subprograms have a lower rank (no recursion)
    depth: int = 0             # structural nesting (jump bodies, IFT, loops, #if)
    loops: int = 0             # enclosing loops
    mult: int = 1              # worst-case repetitions of this code per call (product of loop bounds)
    top: bool = False          # top level of the main program
    job: _Sub | None = None    # the submit job whose own subprogram this is (not a subprogram it calls)

    @property
    def in_main(self) -> bool:
        """Code of the main program (also nested in its jumps, structures and loops)."""
        return self.rank == MAIN_RANK

    @property
    def may_nest(self) -> bool:
        return self.depth < 3

    @property
    def may_loop(self) -> bool:
        """Another loop fits: bounded nesting and a bounded instruction count per cycle."""
        return self.loops < 2 and self.may_nest and self.mult <= 8

    def deeper(self, **kw) -> "_Ctx":
        return dataclasses.replace(self, depth=self.depth + 1, top=False, **kw)

    def loop_body(self, times: int) -> "_Ctx":
        """The context of a loop body that runs at most `times` times per pass (0 counts as once)."""
        return self.deeper(loops=self.loops + 1, mult=self.mult * max(times, 1))


def _string_no(operand: str) -> int | None:
    """The string number of a constant module parameter when it is a valid one of the generated strings."""
    if operand.startswith("K") and operand[1:].isdigit() and int(operand[1:]) < N_STRINGS:
        return int(operand[1:])
    return None


# ---------------------------------------------------------------------------------------------------------
# the generator


class _Gen:
    def __init__(self, seed: int, size: int, features: frozenset[str], faults: bool):
        self.seed = seed
        self.rng = random.Random(seed)
        self.size = max(1, size)
        self.features = features
        self.faults = faults
        self.lines: list[str] = []
        self.cost = 0
        self.cur: _Unit | None = None
        self.sym: dict[tuple[str, int], str] = {}          # global .def symbols: (kind, addr) -> name
        self.const_syms: list[str] = []
        self.auto_bits: list[str] = []
        self.auto_words: list[str] = []
        self.def_lines: list[str] = []
        self.timers: dict[int, str] = {}
        self.counters: dict[int, int] = {}
        self.reserved_words = 0
        self.reserved_doubles = 0
        self.reserved_edges = 0
        self.reserved_subbits = 0
        self.defines: list[tuple[str, str]] = []           # of OEM.cfg, made first when "cfg" is on
        self.strings_used: set[int] = set()
        self.dyn_words: list[str] = []
        self.all_subs: list[_Sub] = []
        self.jobs: list[_Sub] = []                         # submit jobs (never called with CM)

    # ---------------------------------------------------------------- emission

    def has(self, feature: str) -> bool:
        return feature in self.features

    def chance(self, p: float) -> bool:
        return self.rng.random() < p

    def op(self, mnemonic: str, operand: str | None = None) -> None:
        self.cost += 1
        if self.has("case_mix") and self.chance(0.04):
            mnemonic = mnemonic.lower()
        self.lines.append(f"{mnemonic:<6}{operand}" if operand is not None else mnemonic)

    def put(self, line: str) -> None:
        self.lines.append(line)

    def label(self, name: str) -> None:
        self.lines.append(f"LBL {name}")

    # ---------------------------------------------------------------- operands

    def name(self, kind: str, addr: int) -> str:
        unit = self.cur
        local = unit.local_syms.get((kind, addr)) if unit is not None else None
        if local is not None and self.chance(0.6):
            return local
        s = self.sym.get((kind, addr))
        if s is not None and self.chance(0.5):
            return s
        if self.has("case_mix") and self.chance(0.03):
            return f"{kind} {addr}"
        return f"{kind}{addr}"

    def inp(self) -> str:
        return self.name("I", self.rng.randrange(N_INPUTS))

    def mbit(self) -> str:
        a = self.rng.randrange(32) if self.chance(0.7) else self.rng.randrange(M_GEN)
        return self.name("M", a)

    def obit(self) -> str:
        return self.name("O", self.rng.randrange(O_GEN))

    def timer_no(self) -> int:
        return self.reuse_or_add(self.timers, N_TIMERS, TIMER_PRESETS)

    def counter_no(self) -> int:
        return self.reuse_or_add(self.counters, N_COUNTERS, COUNTER_PRESETS)

    def reuse_or_add(self, presets: dict, count: int, choices: tuple) -> int:
        """A timer or counter number, often one already used; a new one gets a preset (written to timers.mp)."""
        used = sorted(presets)
        if used and self.chance(0.6):
            return self.rng.choice(used)
        n = self.rng.randrange(count)
        if n not in presets:
            presets[n] = self.rng.choice(choices)
        return n

    def bit_r(self) -> str:
        r = self.rng.random()
        if r < 0.40:
            return self.inp()
        if r < 0.66:
            return self.mbit()
        if r < 0.76:
            return self.obit()
        if r < 0.81 and self.has("timers"):
            return self.name("T", TIMER_RUNNING + self.timer_no())
        if r < 0.85 and self.has("counters"):
            return self.name("C", COUNTER_RUNNING + self.counter_no())
        if r < 0.90 and self.has("nc"):
            return f"M{self.rng.choice(IF_READ_BITS)}"
        if r < 0.94 and self.auto_bits:
            return self.rng.choice(self.auto_bits)
        return self.mbit()

    def bit_w(self) -> str:
        r = self.rng.random()
        if r < 0.55:
            return self.mbit()
        if r < 0.95 or not self.auto_bits:
            return self.obit()
        return self.rng.choice(self.auto_bits)

    def mem(self, kind: str | None = None, hot: bool = True) -> str:
        kind = kind or self.rng.choice("BWWDD")
        top = 64 if hot and self.chance(0.75) else GEN_BYTES
        size = BYTES_PER_OPERAND[kind]
        addr = self.rng.randrange(top // size) * size
        return self.name(kind, addr)

    def const(self) -> str:
        r = self.rng.random()
        if r < 0.30:
            v = self.rng.randint(-20, 300)
            return f"K+{v}" if v > 0 and self.chance(0.15) else f"K{v}"
        if r < 0.45:
            return f"K{self.rng.choice(EDGE_CONSTS)}"
        if r < 0.60:
            digits = self.rng.randint(1, 8)
            return "K$" + "".join(self.rng.choice("0123456789ABCDEF") for _ in range(digits))
        if r < 0.68:
            return "K%" + "".join(self.rng.choice("01") for _ in range(self.rng.randint(1, 16)))
        if r < 0.80:
            return f"K{self.rng.randint(-2147483648, 2147483647)}"
        if r < 0.88 and self.const_syms:
            return self.rng.choice(self.const_syms)
        return f"K{self.rng.randint(-5000, 70000)}"

    def const_lit(self) -> str:
        """A constant literal (never a symbol), e.g. for KFIELD entries and .def constants."""
        while True:
            c = self.const()
            if c.startswith("K") and not c[1:2].isalpha():
                return c

    def val_r(self) -> str:
        r = self.rng.random()
        if r < 0.35:
            return self.const()
        if r < 0.90:
            return self.mem()
        if r < 0.95 and self.has("nc"):
            return self.rng.choice(IF_READ_WORDS)
        if self.auto_words:
            return self.rng.choice(self.auto_words)
        return self.mem()

    def val_w(self) -> str:
        if self.auto_words and self.chance(0.08):
            return self.rng.choice(self.auto_words)
        return self.mem()

    def count(self) -> str:
        """A shift or bit count: any value (taken mod 32)."""
        r = self.rng.random()
        if r < 0.6:
            return f"K{self.rng.randint(0, 31)}"
        if r < 0.8:
            return f"K{self.rng.choice((-1, -5, -31, -32, 32, 33, 40, 63, 64, 100, -100, 1000))}"
        return self.mem()

    def reserve_word(self) -> str:
        w = LOOP_WORDS + 2 * self.reserved_words
        self.reserved_words += 1
        return f"W{w}"

    def reserve_double(self) -> str:
        d = SUB_DOUBLES + 4 * self.reserved_doubles
        self.reserved_doubles += 1
        return f"D{d}"

    def reserve_edge(self) -> str:
        m = M_EDGE + self.reserved_edges
        self.reserved_edges += 1
        return f"M{m}"

    # ---------------------------------------------------------------- small pieces

    def assigns(self, lo: int = 1, hi: int = 2) -> None:
        for _ in range(self.rng.randint(lo, hi)):
            self.op(self.rng.choices(ASSIGNS, ASSIGN_WEIGHTS)[0], self.bit_w())

    def chain_start(self) -> None:
        r = self.rng.random()
        if r < 0.62:
            self.op("L", self.bit_r())
        elif r < 0.85:
            self.op("LN", self.bit_r())
        elif r < 0.90:
            self.op(self.rng.choice(GATES), self.bit_r())       # acts as L/LN at chain start (5.4)
        elif self.has("compare"):
            self.op("L", self.val_r())
            self.op(self.rng.choice(COMPARES), self.val_r())
        else:
            self.op("L", self.bit_r())

    def gates(self, lo: int = 0, hi: int = 3, level: int = 0) -> None:
        for _ in range(self.rng.randint(lo, hi)):
            if self.has("brackets_logic") and level < 3 and self.chance(0.1):
                self.logic_bracket(level + 1)
            else:
                self.op(self.rng.choice(GATES), self.bit_r())

    def cond(self) -> None:
        """Leaves a condition in LA, usually one that changes from cycle to cycle (inputs, varying words)."""
        r = self.rng.random()
        if r < 0.55 or not (self.has("compare") or self.has("shift")):
            if self.chance(0.7):
                self.op(self.rng.choice(("L", "L", "LN")), self.inp())
            else:
                self.chain_start()
            for _ in range(self.rng.randint(0, 2)):
                self.op(self.rng.choice(GATES), self.inp() if self.chance(0.6) else self.bit_r())
        elif r < 0.9 and self.has("compare"):
            self.op("L", self.dyn_val())
            if self.chance(0.4):
                self.op("A", self.rng.choice(("K1", "K3", "K7", "K15", "K$FF")))
            elif self.chance(0.2):
                self.word_op()
            self.op(self.rng.choice(COMPARES), self.rng.choice((f"K{self.rng.randint(-2, 9)}", self.dyn_val(),
                                                                  self.val_r())))
            if self.chance(0.3):
                self.op(self.rng.choice(GATES), self.bit_r())
        else:
            self.op("L", self.dyn_val())
            self.op("BT", self.count())

    def bit_cond(self) -> None:
        """A condition from bit operands only: WA is left alone."""
        self.op(self.rng.choice(("L", "L", "LN")), self.inp())
        for _ in range(self.rng.randint(0, 2)):
            self.op(self.rng.choice(GATES), self.inp() if self.chance(0.6) else self.bit_r())

    def dyn_val(self) -> str:
        """A word that probably changes while the program runs (written from inputs or accumulated)."""
        if self.dyn_words and self.chance(0.75):
            return self.rng.choice(self.dyn_words)
        return self.mem()

    def word_op(self, x_ok: bool = False) -> None:
        r = self.rng.random()
        operand = "X" if x_ok and self.chance(0.2) else self.val_r()
        if r < 0.5:
            a = self.rng.choice(ARITH)
            if a in ("/", "MOD") and self.chance(0.25):
                operand = self.rng.choice(("K0", self.mem()))
            self.op(a, operand)
        elif r < 0.8:
            self.op(self.rng.choice(GATES), operand)
        elif r < 0.9 and self.has("shift"):
            self.op(self.rng.choice(("<<", ">>")), self.count())
        elif self.has("shift"):
            self.op(self.rng.choice(("BS", "BC")), self.count())
        else:
            self.op("+", operand)

    def copy_error_marker(self) -> None:
        """Reads an arithmetic error marker, so that a wrong overflow or division-by-zero flag shows."""
        self.op("L", f"M{self.rng.choice(ARITH_ERROR_MARKERS)}")
        self.op("=", self.bit_w())

    def word_load(self) -> None:
        r = self.rng.random()
        if r < 0.8:
            self.op("L", self.val_r())
        elif r < 0.9:
            self.op("L-", self.val_r())
        else:
            self.op("LN", self.val_r())

    # ---------------------------------------------------------------- brackets

    def logic_bracket(self, level: int) -> None:
        """An opening logic bracket after a logic instruction (LOGIC mode), its body, and ']'."""
        self.op(self.rng.choice(GATES) + "[")
        r = self.rng.random()
        if r < 0.65 or not self.has("compare"):
            self.chain_start()
            self.gates(0, 2, level)
        elif r < 0.85 or not self.has("brackets_word"):
            self.op("L", self.val_r())
            self.op(self.rng.choice(COMPARES), self.val_r())
            self.gates(0, 1, level)
        else:
            self.op("L", self.val_r())
            self.word_bracket("compare", level + 1)
        if self.chance(0.1):
            self.op("=", self.bit_w())            # an assignment inside a bracket closes the inner chain
            if self.chance(0.5):
                self.op(self.rng.choice(GATES), self.bit_r())
        self.op("]")

    def word_bracket(self, kind: str, level: int) -> None:
        """An opening word bracket right after a word instruction (WORD mode), its body, and ']'."""
        if kind == "arith":
            mnemonic = self.rng.choice(ARITH)
        elif kind == "compare":
            mnemonic = self.rng.choice(COMPARES)
        else:
            mnemonic = self.rng.choice(GATES)
        self.op(mnemonic + "[")
        if mnemonic in ("/", "MOD") and self.chance(0.3):
            self.op("L", self.mem())
            self.op("A", "K0")                    # inner value 0: division by zero in a bracket (17b.4)
        else:
            self.word_load()
            for _ in range(self.rng.randint(0, 2)):
                self.word_op()
            if level < 3 and self.chance(0.25):
                self.word_bracket(self.rng.choice(("arith", "arith", "wlogic")), level + 1)
            if kind != "compare" and self.has("compare") and self.chance(0.08):
                self.op(self.rng.choice(COMPARES), self.val_r())   # LA changes, WA (the bracket's value) not
                self.op("=", self.bit_w())
        self.op("]")

    # ---------------------------------------------------------------- statements

    def stmt_kinds(self, ctx: _Ctx) -> list[tuple[Callable[[_Ctx], None], float]]:
        f = self.has
        nest_ok, loop_ok = ctx.may_nest, ctx.may_loop
        kinds: list[tuple[Callable[[_Ctx], None], float, bool]] = [
            (self.s_logic, 14, f("logic")),
            (self.s_word, 11, f("word")),
            (self.s_accumulate, 7, f("word")),
            (self.s_overlap, 3, f("word")),
            (self.s_compare, 7, f("compare")),
            (self.s_shift, 4, f("shift")),
            (self.s_brackets_logic, 5, f("brackets_logic") and f("logic")),
            (self.s_brackets_word, 5, f("brackets_word")),
            (self.s_stack, 3, f("stack")),
            (self.s_jump, 5, f("jumps") and nest_ok),
            (self.s_loop, 3, f("loops") and loop_ok),
            (self.s_ift, 5, f("struct") and nest_ok),
            (self.s_while, 2, f("while") and loop_ok),
            (self.s_repeat, 2, f("repeat") and loop_ok),
            (self.s_call, 7, f("calls") and bool(self.callable_subs(ctx))),
            (self.s_case, 2, f("case") and bool(self.callable_subs(ctx, case=True))),
            (self.s_index, 4, f("index")),
            (self.s_kfield, 2, f("kfield")),
            (self.s_timer, 4, f("timers")),
            (self.s_counter, 3, f("counters")),
            (self.s_edge, 3, f("edges")),
            (self.s_nc, 3, f("nc")),
            (self.s_cfg, 3, f("cfg") and nest_ok),
            (self.s_extended, 3, f("extended")),
            (self.s_bitpack, 3, f("bitpack")),
            (self.s_string, 1, f("strings")),
            (self.s_main_em, 0.6, f("main_em") and ctx.top),
            (self.s_carry, 1, f("acc_carry")),
            (self.s_flow, 4, f("reg_flow") and nest_ok),
            (self.s_write_input, 0.5, f("write_input")),
            (self.s_jobs, 3 if ctx.job else 1.5, f("submit") and bool(self.jobs) and (ctx.in_main or ctx.job is not None)),
            (self.s_module, 4 if ctx.job else 2.5, f("plc_modules") and f("stack")),
        ]
        return [(fn, w) for fn, w, ok in kinds if ok]

    def stmt(self, ctx: _Ctx) -> None:
        kinds = self.stmt_kinds(ctx)
        if not kinds:                      # every feature off: still a valid program
            self.op("L", "K0")
            self.op("=", self.mem())
            return
        fns = [k[0] for k in kinds]
        weights = [k[1] for k in kinds]
        self.rng.choices(fns, weights)[0](ctx)

    # submit jobs and PLC modules ---------------------------------------------------------------------

    def s_jobs(self, ctx: _Ctx) -> None:
        if ctx.job is not None:
            self.job_op_in_job(ctx, ctx.job)
        else:
            self.job_op_in_main(ctx)

    def guarded(self, emit: Callable[[], None]) -> None:
        """emit() behind a condition (a forward jump or IFT) when those features are on, else unconditionally."""
        r = self.rng.random()
        if r < 0.45 and self.has("jumps"):
            skip = self.cur.fresh("Lb")
            self.cond()
            self.op(self.rng.choice(("JPF", "JPT")), skip)
            emit()
            self.label(skip)
        elif r < 0.8 and self.has("struct"):
            self.cond()
            self.op(self.rng.choice(("IFT", "IFF")))
            emit()
            self.op("ENDI")
        else:
            emit()

    def submit_job(self, job: _Sub) -> None:
        job.calls += 1
        self.op("SUBM", job.name)
        self.op("=", job.ident)
        self.cost += job.cost
        if self.chance(0.25):
            if self.has("compare") and self.chance(0.6):
                self.op("==", "K0")                       # the queue was full
                self.assigns(1, 1)
            else:
                self.op("=", self.val_w())

    def job_ident(self, job: _Sub) -> str:
        r = self.rng.random()
        if r < 0.85:
            return job.ident
        if r < 0.95:
            return f"K{self.rng.randint(0, 9)}"               # identifiers are numbered 1, 2, ... from the start
        return self.mem()

    def reply(self, job: _Sub) -> None:
        self.op("RPLY", self.job_ident(job))
        if self.has("compare") and self.chance(0.4):
            self.op(self.rng.choice(("==", "<>", ">=")), f"K{self.rng.randint(0, 2)}")
            self.assigns(1, 1)
        else:
            self.op("=", self.val_w())

    def job_op_in_main(self, ctx: _Ctx) -> None:
        """SUBM of a job (its identifier stored), RPLY of a job's state, CAN of a waiting job."""
        job = self.rng.choice(self.jobs)
        r = self.rng.random()
        if r < 0.5:
            if self.has("jumps") and self.has("compare") and self.chance(0.3):
                skip = self.cur.fresh("Lb")               # queue it unless it is still queued (the usual idiom)
                self.op("RPLY", job.ident)
                self.op("==", "K0")
                self.op("JPF", skip)
                self.submit_job(job)
                self.label(skip)
            else:
                self.guarded(lambda: self.submit_job(job))
        elif r < 0.8:
            self.reply(job)
        else:
            self.guarded(lambda: self.op("CAN", self.job_ident(job)))

    def job_op_in_job(self, ctx: _Ctx, job: _Sub) -> None:
        """Inside a job's own subprogram: RPLY of itself (1), SUBM (0: no nesting), CAN of itself or another job."""
        r = self.rng.random()
        if r < 0.3:
            self.reply(job)
        elif r < 0.5:
            self.op("SUBM", self.rng.choice(self.jobs).name)
            self.op("=", self.val_w())
        elif r < 0.8:
            self.guarded(lambda: self.op("CAN", job.ident))          # the running job ends here
        else:
            other = self.rng.choice(self.jobs)
            if self.chance(0.5):
                self.reply(other)
            else:
                self.guarded(lambda: self.op("CAN", other.ident))

    def module_param(self, kind: str) -> str:
        r = self.rng.random()
        if kind == "any" or (r < 0.06 and kind != "str"):     # a string number must be a constant in the ST
            return self.val_r() if self.chance(0.6) else self.const()
        if kind == "small":
            return f"K{self.rng.randint(-1, 12)}"
        if kind == "mask":
            return f"K{self.rng.choice((0, 1, 3, 5, 255, 256, 65535, -1))}"
        if kind == "hour":
            return f"K{self.rng.randint(-4, 8)}"
        if kind == "addr":
            return f"K{self.rng.randrange(GEN_BYTES)}" if r < 0.9 else f"K{self.rng.choice((-1, 9999, 10000))}"
        if kind == "count":
            # 63 bytes give 126 hex digits, all an ST string holds; 64 (128 digits, fine on the control) is a
            # documented target limit (docs/modules.md), 65 and more are error 1
            return f"K{self.rng.randint(0, 16)}" if r < 0.9 else f"K{self.rng.choice((-1, 63, 65, 100))}"
        if kind == "exp":
            return f"K{self.rng.randint(-6, 6)}" if r < 0.9 else f"K{self.rng.choice((-11, 11, 100))}"
        if kind == "str":
            return f"K{self.rng.randrange(N_STRINGS)}" if r < 0.93 else f"K{self.rng.choice((-1, 100))}"
        if kind == "status":
            return f"K{self.rng.randint(0, 7)}" if r < 0.9 else f"K{self.rng.choice((-1, 255, 256))}"
        if kind == "axis":
            return f"K{self.rng.randint(-1, 5)}" if r < 0.9 else "K16"
        if kind == "info":
            return f"K{self.rng.randint(0, 11)}"
        raise ValueError(kind)

    def mp_params(self) -> list[str]:
        """(number, index) of a machine parameter of timers.mp, or of one that does not exist."""
        known = [(4110, n) for n in sorted(self.timers)] + [(4120, n) for n in sorted(self.counters)]
        if known and self.chance(0.75):
            number, index = self.rng.choice(known)
        else:
            number, index = self.rng.choice(((4110, 30), (1234, 0), (4120, 99)))
        return [f"K{number}", f"K{index}"]

    def set_string(self, s: int, numeric: bool) -> None:
        """A string with (or without) a number in it, or hex digits, for the string modules."""
        if numeric:
            text = self.rng.choice(("12.5", "-3,25", "abc 42x", "+7", "0.001", "X-1.5Y", "2147483648", "", "no",
                                    "1.2.3", "-", "007"))
        else:
            text = self.rng.choice(("0A1B", "FF", "00ff7E", "123", "G1", "", "DEADBEEF", "7f80"))
        self.op("L", f'S"{text}"')
        self.op("=", f"S{s}")
        self.strings_used.add(int(s))

    def s_module(self, ctx: _Ctx) -> None:
        """Parameters pushed in order, CM 9xxx, results pulled in order; the error marker and code read back."""
        r = self.rng.random()
        if r < 0.3:
            number = self.rng.choice(sorted(PURE_MODULES))
            kinds, nresults = PURE_MODULES[number]
        elif ctx.job is not None and r < 0.75:
            number = self.rng.choice(SUBMIT_ONLY_MODULES)
            kinds, nresults = SYS_MODULES[number]
        else:
            number = self.rng.choice(sorted(SYS_MODULES))
            kinds, nresults = SYS_MODULES[number]
        params = [self.module_param(k) if k not in ("mp", "mpindex") else "" for k in kinds]
        if kinds[:2] == ("mp", "mpindex"):
            params[:2] = self.mp_params()
        strings = {i: _string_no(p) for i, (p, k) in enumerate(zip(params, kinds)) if k == "str"}
        if number in (9052, 9070, 9054) and strings[0] is not None and self.chance(0.7):
            self.set_string(strings[0], numeric=number != 9054)
        if number in (9053, 9054):
            # the byte memory must be one array in the ST: that takes an indexed access in the program
            self.set_x(7)
            self.op("L", f"B{self.rng.randrange(IDX_BYTE_MAX)}[X]")
            self.op("=", self.val_w())
        for p in params:
            self.op("PS", p)
        if number in SYS_MODULES and len(kinds) == nresults and self.chance(0.6):
            # A conditional call: whether it happens or not, the pulls below take as many words as were pushed.
            self.op("L", self.bit_r())
            self.op(self.rng.choice(("CMT", "CMF")), str(number))
        else:
            self.op("CM", str(number))
        for _ in range(nresults):
            if self.chance(0.75):
                self.op("PL", self.val_w())
            else:
                self.op("PLW")
                self.op("=", self.val_w())
        # what the module wrote, read back so that the co-simulation compares it
        written = {9050: 2, 9053: 1, 9070: 1}.get(number)
        if written is not None and strings[written] is not None:
            self.op("L", f"S{strings[written]}")
            self.op("=", f"S{self.rng.randrange(N_STRINGS)}")
        if number == 9054 and re.fullmatch(r"K\d+", params[1]) and int(params[1][1:]) < GEN_BYTES:
            addr = int(params[1][1:])
            self.touch_bytes(addr, min(16, GEN_BYTES - addr))
        if self.chance(0.6):
            self.op("L", "M4203")
            self.op("=", self.bit_w())
        if self.chance(0.5):
            self.op("L", "W1022")
            self.op("=", self.val_w())

    def body(self, ctx: _Ctx, lo: int = 1, hi: int = 3) -> None:
        for _ in range(self.rng.randint(lo, hi)):
            self.stmt(ctx)

    # logic ------------------------------------------------------------------------------------------

    def s_logic(self, ctx: _Ctx) -> None:
        self.chain_start()
        self.gates(0, 4)
        self.assigns(1, 3)
        if self.chance(0.12):                  # a gate right after an assignment acts as a load (5.4)
            self.op(self.rng.choice(GATES), self.bit_r())
            self.gates(0, 1)
            self.assigns(1, 1)

    def s_compare(self, ctx: _Ctx) -> None:
        self.op("L", self.val_r())
        if self.chance(0.3):
            self.word_op()
        self.op(self.rng.choice(COMPARES), self.val_r())
        if self.has("logic"):
            self.gates(0, 2)
        self.assigns(1, 2)

    # word -------------------------------------------------------------------------------------------

    def s_word(self, ctx: _Ctx) -> None:
        if self.chance(0.08):
            a, mnemonic, b = self.rng.choice(ARITH_EDGE_CASES)
            # L- of the most negative value would overflow before the operation under test
            self.op(self.rng.choice(("L", "L-")) if a != "K-2147483648" else "L", a)
            self.op(mnemonic, b)
            self.op("=", self.val_w())
            self.copy_error_marker()
            return
        self.word_load()
        for _ in range(self.rng.randint(1, 4)):
            self.word_op()
            if self.chance(0.15):
                self.op("=", self.val_w())
        self.op("=", self.val_w())
        if self.chance(0.2):
            self.op("=", self.val_w())
        if self.chance(0.25):
            self.copy_error_marker()

    def s_accumulate(self, ctx: _Ctx) -> None:
        """Words that change from cycle to cycle: packed inputs, sums, counts of input cycles."""
        r = self.rng.random()
        if r < 0.4 and self.has("bitpack"):
            base = {"LB": 24, "LW": 16, "LD": 0}
            mn = self.rng.choice(("LB", "LB", "LW", "LW", "LD"))
            start = self.rng.randint(0, base[mn])
            self.op(mn, f"I{start}")
            if self.chance(0.5):
                self.word_op()
            acc = self.val_w()
        elif r < 0.7:
            acc = self.mem(self.rng.choice("WDD"))
            self.op("L", acc)
            self.op(self.rng.choice(("+", "+", "-")), self.rng.choice((self.dyn_val(), self.const(), "K1")))
        elif r < 0.8:
            acc = self.mem("D")
            self.op("L", acc)
            self.op("x", self.rng.choice(("K3", "K7", "K-5", "K257", self.mem())))
            self.op("+", self.rng.choice(("K1", "K13", self.mem())))
        else:
            self.op("L", self.inp())
            if self.has("logic"):
                self.op(self.rng.choice(("A", "O", "XO")), self.inp())
            acc = self.mem()
            if self.has("jumps"):
                skip = self.cur.fresh("Lb")
                self.op("JPF", skip)
                self.op("L", acc)
                self.op("+", self.rng.choice(("K1", "K3", "K-1", "K100")))
                self.op("=", acc)
                self.label(skip)
                self.dyn_words.append(acc)
                return
            self.op("L", acc)
            self.op("+", "K1")
        self.op("=", acc)
        self.dyn_words.append(acc)

    def s_overlap(self, ctx: _Ctx) -> None:
        """A double word written, then read back through its bytes and words (5.2)."""
        base = self.rng.randrange(16) * 4
        self.op("L", self.rng.choice((self.const(), "K$12345678", "K-2", "K$80FF017F", self.mem())))
        self.op("=", self.name("D", base))
        for i in range(self.rng.randint(1, 3)):
            kind = self.rng.choice("BW")
            off = self.rng.randrange(4) if kind == "B" else self.rng.choice((0, 2))
            self.op("L" if i == 0 else self.rng.choice(("+", "XO", "-", "O")), self.name(kind, base + off))
            if self.chance(0.4):
                kind = self.rng.choice("BW")
                off = self.rng.randrange(4) if kind == "B" else self.rng.choice((0, 2))
                self.op("=", self.name(kind, base + off))
        self.op("=", self.mem())

    def s_shift(self, ctx: _Ctx) -> None:
        r = self.rng.random()
        self.word_load()
        if r < 0.5:
            for _ in range(self.rng.randint(1, 3)):
                self.op(self.rng.choice(("<<", ">>", "<<", ">>", "BS", "BC")), self.count())
            self.op("=", self.val_w())
        else:
            if self.chance(0.4):
                self.op(self.rng.choice(("BS", "BC", "<<")), self.count())
            self.op("BT", self.count())
            if self.has("logic"):
                self.gates(0, 1)
            self.assigns(1, 2)

    # brackets ---------------------------------------------------------------------------------------

    def s_brackets_logic(self, ctx: _Ctx) -> None:
        if self.chance(0.15):
            # load bracket: the chain is closed by the assignment, the bracket's mode is LOGIC (A-04)
            self.chain_start()
            self.op("=", self.bit_w())
            self.logic_bracket(1)
        else:
            self.chain_start()
            self.gates(0, 1)
            if self.has("extended") and self.chance(0.1):
                self.op(self.rng.choice(("INC", "DEC")), self.mem())   # last_acc NONE: LOGIC mode, chain kept
            self.logic_bracket(1)
        self.gates(0, 2, 1)
        self.assigns(1, 2)

    def s_brackets_word(self, ctx: _Ctx) -> None:
        self.word_load()
        if self.chance(0.3):
            self.word_op()
        kind = self.rng.choice(("arith", "arith", "compare", "wlogic"))
        if kind != "wlogic" and self.has("extended") and self.chance(0.1):
            self.op(self.rng.choice(("INC", "DEC")), self.mem())      # last_acc NONE: WORD mode for + - x / ==
        self.word_bracket(kind, 1)
        if kind == "compare":
            if self.has("logic"):
                self.gates(0, 1)
            self.assigns(1, 2)
        else:
            if self.chance(0.4):
                self.word_op()
            self.op("=", self.val_w())
            if self.chance(0.2):
                self.copy_error_marker()

    # stack ------------------------------------------------------------------------------------------

    def s_stack(self, ctx: _Ctx) -> None:
        x_ok = self.has("index")
        pushed: list[str] = []              # "bit" (one word) or "val" (two words), in push order
        for _ in range(self.rng.randint(1, 4)):
            r = self.rng.random()
            if r < 0.25:
                self.op("PS", self.bit_r())
                pushed.append("bit")
            elif r < 0.55:
                self.op("PS", self.val_r())
                pushed.append("val")
            elif r < 0.75:
                self.word_load()
                if self.chance(0.5):
                    self.word_op()
                if self.chance(0.3):
                    self.barrier(ctx)                 # WA crosses a label, call or CASE before it is pushed
                self.op("PSW")
                pushed.append("val")
            elif r < 0.9 or not x_ok:
                self.chain_start()
                self.gates(0, 1)
                self.op("PSL")
                pushed.append("bit")
            else:
                self.op("PSX")
                pushed.append("val")
        if self.chance(0.3):
            self.op("L", self.val_r())
            self.word_op()
            self.op("=", self.val_w())
        if self.has("stack_mixed") and self.chance(0.25):
            words = sum(1 if p == "bit" else 2 for p in pushed)
            pops: list[str] = []
            while words:
                if words >= 2 and self.chance(0.5):
                    pops.append("val")
                    words -= 2
                else:
                    pops.append("bit")
                    words -= 1
        else:
            pops = list(reversed(pushed))
        for p in pops:
            r = self.rng.random()
            if p == "bit":
                self.pull_bit(to_operand=r < 0.6)
            else:
                if r < 0.55:
                    self.op("PL", self.val_w())
                elif r < 0.85 or not x_ok:
                    self.op("PLW")
                    if self.chance(0.3):
                        self.word_op()
                    self.op("=", self.val_w())
                else:
                    self.op("PLX")
                    self.op("L", "X")
                    self.op("=", self.val_w())

    def pull_bit(self, to_operand: bool) -> None:
        """Pulls one bit off the data stack: into a bit operand, or into LA and then assigned."""
        if to_operand:
            self.op("PL", self.bit_w())
        else:
            self.op("PLL")
            self.assigns(1, 1)

    def barrier(self, ctx: _Ctx) -> None:
        """A point where control flow meets, leaving WA and LA alone: a label, a call, a CASE table."""
        subs = self.plain_subs(ctx)
        r = self.rng.random()
        if subs and r < 0.35 and self.has("case"):
            self.op("CASE", self.mem("B"))
            s = self.pick_sub(subs)
            self.op("CM", s.name)
            self.op("ENDC")
            self.cost += s.cost
        elif subs and r < 0.6:
            s = self.pick_sub(subs)
            self.op("CM", s.name)
            self.cost += s.cost
        elif self.has("jumps"):
            lbl = self.cur.fresh("Lb")
            self.op("JP", lbl)
            self.label(lbl)

    # jumps and loops --------------------------------------------------------------------------------

    def s_jump(self, ctx: _Ctx) -> None:
        unit = self.cur
        r = self.rng.random()
        if r < 0.5:
            skip = unit.fresh("Lb")
            self.cond()
            self.op(self.rng.choice(("JPF", "JPT")), skip)
            self.body(ctx.deeper(), 1, 3)
            self.label(skip)
        elif r < 0.65:
            skip = unit.fresh("Lb")
            self.op("JP", skip)
            saved = self.cost
            self.body(ctx.deeper(), 1, 2)         # dead code
            self.cost = saved
            self.label(skip)
        elif r < 0.8:
            keep = unit.fresh("Lb")                 # a jump keeps LA and WA (A-54)
            self.chain_start()
            self.gates(0, 1)
            if self.chance(0.5):
                self.word_load()
            self.op(self.rng.choice(("JP", "JPT", "JPF")), keep)
            if self.chance(0.5):
                self.op("L", self.bit_r())
                self.op("L", self.val_r())
            self.label(keep)
            self.assigns(1, 1)
            self.op("=", self.val_w())
        elif r < 0.9 or not self.has("goto_mix"):
            other, end = unit.fresh("Lb"), unit.fresh("Lb")
            self.cond()
            self.op("JPF", other)
            self.body(ctx.deeper(), 1, 2)
            self.op("JP", end)
            self.label(other)
            self.body(ctx.deeper(), 1, 2)
            self.label(end)
        else:                                       # crossing forward jumps: A ... B ... LBL A ... LBL B
            first, second = unit.fresh("Lb"), unit.fresh("Lb")
            self.cond()
            self.op(self.rng.choice(("JPF", "JPT")), first)
            self.body(ctx.deeper(), 1, 1)
            self.cond()
            self.op(self.rng.choice(("JPF", "JPT", "JP")), second)
            self.body(ctx.deeper(), 1, 1)
            self.label(first)
            self.body(ctx.deeper(), 1, 1)
            self.label(second)

    def loop_bound(self) -> tuple[str, int]:
        """A loop bound operand (constant or masked data in a reserved word) and its largest value."""
        if self.chance(0.5):
            n = self.rng.randint(0, 6)
            return f"K{n}", n
        bound = self.reserve_word()
        self.op("L", self.dyn_val())
        self.op("A", "K7")
        self.op("=", bound)
        return bound, 7

    def s_loop(self, ctx: _Ctx) -> None:
        unit = self.cur
        r = self.rng.random()
        if r < 0.2 and self.has("index"):
            self.x_loop(ctx)
            return
        cnt = self.reserve_word()
        bound, n = self.loop_bound()
        top = unit.fresh("Lp")
        inner = ctx.loop_body(n)
        if r < 0.55:                          # test at the end
            exit_label = unit.fresh("Lp") if self.chance(0.3) else None
            self.set_zero(cnt)
            self.label(top)
            start = self.cost
            self.body(inner, 1, 2)
            if exit_label:                    # leave the loop early: a jump out of the loop body
                self.cond()
                self.op(self.rng.choice(("JPT", "JPF")), exit_label)
                self.body(inner, 0, 1)
            self.increment(cnt)
            if self.chance(0.5):
                self.op("<", bound)
                self.op("JPT", top)
            else:
                self.op(">=", bound)
                self.op("JPF", top)
            if exit_label:
                self.label(exit_label)
        else:                                 # test at the top, counting down or up
            end = unit.fresh("Lp")
            down = self.chance(0.5)
            self.op("L", bound if down else "K0")
            self.op("=", cnt)
            self.label(top)
            start = self.cost
            self.op("L", cnt)
            if down:
                self.op("<=", "K0")
            else:
                self.op(">=", bound)
            self.op("JPT", end)
            self.body(inner, 1, 3)
            self.op("L", cnt)
            self.op("-" if down else "+", "K1")
            self.op("=", cnt)
            self.op("JP", top)
            self.label(end)
        self.charge_repeats(start, n)

    def x_loop(self, ctx: _Ctx) -> None:
        """A loop with X as the counter over indexed tables; its body never changes X."""
        unit = self.cur
        top = unit.fresh("Lp")
        n = self.rng.randint(1, 8)
        src = self.rng.randrange(IDX_BYTE_MAX)
        dst = self.rng.randrange(IDX_BYTE_MAX)
        self.set_zero("X")
        self.label(top)
        start = self.cost
        self.op("L", f"B{src}[X]")
        self.word_op(x_ok=True)
        self.op("=", f"B{dst}[X]")
        if self.chance(0.5):
            self.op("L", f"I{self.rng.randrange(N_INPUTS - n)}[X]")
            self.op(self.rng.choice(GATES), self.bit_r())
            self.op("=", f"M{M_TABLE + 10 * self.rng.randrange(8)}[X]")
        if self.has("extended") and self.chance(0.6):
            self.op("INCX")
        else:
            self.increment("X")
        self.op("L", "X")
        self.op("<", f"K{n}")
        self.op("JPT", top)
        self.charge_repeats(start, n)
        self.touch_bytes(dst, 8)

    def set_zero(self, word: str) -> None:
        self.op("L", "K0")
        self.op("=", word)

    def increment(self, word: str) -> None:
        """word + 1 without INC/INCW/INCX, which are optional instructions (feature "extended", A-23)."""
        self.op("L", word)
        self.op("+", "K1")
        self.op("=", word)

    def charge_repeats(self, start: int, times: int) -> None:
        """The code emitted since cost `start` was counted once but runs up to `times` times (0 counts once)."""
        self.cost += (self.cost - start) * max(times, 1)

    def touch_bytes(self, base: int, length: int) -> None:
        """Re-store the bytes of an indexed table in place so that the co-simulation compares them."""
        first = base - base % 4
        for a in range(first, base + length, 4):
            self.op("L", f"D{a}")
            self.op("=", f"D{a}")

    def s_ift(self, ctx: _Ctx) -> None:
        if self.has("goto_mix") and self.has("loops") and ctx.may_loop and self.chance(0.15):
            # a loop whose backward jump sits inside an IFT: LBL top ... IFT ... JPT top ... ENDI
            cnt = self.reserve_word()
            n = self.rng.randint(1, 5)
            top = self.cur.fresh("Lp")
            inner = ctx.loop_body(n)
            self.set_zero(cnt)
            self.label(top)
            start = self.cost
            self.body(inner, 1, 2)
            self.cond()
            self.op(self.rng.choice(("IFT", "IFF")))
            self.body(inner, 0, 1)
            self.increment(cnt)
            self.op("<", f"K{n}")
            self.op("JPT", top)
            self.body(inner, 0, 1)
            self.op("ENDI")
            self.charge_repeats(start, n)
            return
        out = self.cur.fresh("Lb") if self.has("jumps") and self.chance(0.12) else None
        self.cond()
        self.op(self.rng.choice(("IFT", "IFT", "IFF")))
        self.body(ctx.deeper(), 1, 3)
        if out:                                 # a jump out of the structure to the end of the block
            self.cond()
            self.op(self.rng.choice(("JPT", "JPF", "JP")), out)
            self.body(ctx.deeper(), 1, 1)
        if self.chance(0.45):
            self.op("ELSE")
            self.body(ctx.deeper(), 1, 2)
        self.op("ENDI")
        if self.has("brackets_logic") and self.chance(0.08):
            self.logic_bracket(1)                     # mode LOGIC, chain closed: a load bracket (A-04)
            self.assigns(1, 1)
        if out:
            self.body(ctx.deeper(), 0, 1)
            self.label(out)

    def s_while(self, ctx: _Ctx) -> None:
        cnt = self.reserve_word()
        bound, n = self.loop_bound()
        true_form = self.chance(0.6)
        self.set_zero(cnt)

        def test() -> None:
            self.op("L", cnt)
            self.op("<" if true_form else ">=", bound)

        test()
        self.op("WHILET" if true_form else "WHILEF")
        start = self.cost
        inner = ctx.loop_body(n)
        self.body(inner, 1, 2)
        out = self.break_out(inner)
        self.increment(cnt)
        test()
        self.op("ENDW")
        self.charge_repeats(start, n)
        if out:
            self.label(out)

    def break_out(self, ctx: _Ctx) -> str | None:
        """Maybe a conditional jump out of a loop body to a label right after the loop (returned)."""
        if not (self.has("goto_mix") and self.has("jumps") and self.chance(0.2)):
            return None
        out = self.cur.fresh("Lb")
        self.cond()
        self.op(self.rng.choice(("JPT", "JPF")), out)
        self.body(ctx, 0, 1)
        return out

    def s_repeat(self, ctx: _Ctx) -> None:
        cnt = self.reserve_word()
        bound, n = self.loop_bound()
        self.set_zero(cnt)
        self.op("REPEAT")
        start = self.cost
        inner = ctx.loop_body(n)
        self.body(inner, 1, 2)
        out = self.break_out(inner)
        self.increment(cnt)
        if self.chance(0.5):
            self.op(">=", bound)
            self.op("UNTILT")
        else:
            self.op("<", bound)
            self.op("UNTILF")
        self.charge_repeats(start, n)
        if out:
            self.label(out)

    # calls ------------------------------------------------------------------------------------------

    def callable_subs(self, ctx: _Ctx, case: bool = False) -> list[_Sub]:
        """Subprograms of a lower rank, small enough for the loops around ctx; case: none from the data stack."""
        unit = ctx.unit
        limit = 800 // ctx.mult
        found = []
        for s in self.all_subs:
            if s.rank >= ctx.rank or s.cost > limit:
                continue
            if case and s.kind in ("stack", "bitstack"):
                continue
            if s.unit is unit or (s.exported and s.unit in unit.uses):
                found.append(s)
        return found

    def plain_subs(self, ctx: _Ctx) -> list[_Sub]:
        """Callable subprograms that leave WA, LA and the data stack alone."""
        if not self.has("calls"):
            return []
        return [s for s in self.callable_subs(ctx) if s.kind == "plain"]

    def pick_sub(self, subs: list[_Sub]) -> _Sub:
        """Subprograms not called yet are preferred, so that few of them stay dead."""
        s = self.rng.choices(subs, [1 if s.calls else 4 for s in subs])[0]
        s.calls += 1
        return s

    def s_call(self, ctx: _Ctx) -> None:
        self.call_sub(ctx, self.pick_sub(self.callable_subs(ctx)))

    def call_sub(self, ctx: _Ctx, s: _Sub) -> None:
        if s.kind == "plain":
            r = self.rng.random()
            if r < 0.5:
                self.op("CM", s.name)
            else:
                self.cond()
                self.op("CMT" if r < 0.75 else "CMF", s.name)
        elif s.kind == "wa":
            if self.chance(0.3):
                self.cond()
                self.word_load()
                self.op(self.rng.choice(("CMT", "CMF")), s.name)
            else:
                self.word_load()
                self.op("CM", s.name)
                if self.has("brackets_word") and self.chance(0.2):
                    self.word_bracket("arith", 2)     # after CM last_acc is NONE: the bracket is in WORD mode
            self.op("=", self.val_w())
        elif s.kind == "la":
            self.chain_start()
            self.gates(0, 1)
            self.op("CM", s.name)
            self.assigns(1, 2)
        elif s.kind == "stack":
            for _ in range(s.params):
                self.op("PS", self.val_r())
            self.op("CM", s.name)
            if self.chance(0.6):
                self.op("PL", self.val_w())
            else:
                self.op("PLW")
                self.op("=", self.val_w())
        else:                                   # bitstack
            for _ in range(s.params):
                self.op("PS", self.bit_r())
            self.op("CM", s.name)
            self.pull_bit(to_operand=self.chance(0.6))
        self.cost += s.cost

    def s_case(self, ctx: _Ctx) -> None:
        subs = self.callable_subs(ctx, case=True)
        if self.chance(0.7):
            sel = self.mem("B")
            self.op("L", self.dyn_val())
            self.op("A", self.rng.choice(("K3", "K7", "K1")))
            self.op("=", sel)
        elif self.chance(0.8):
            sel = self.mem(self.rng.choice("BBWWD"))          # often out of range: nothing is called
        else:
            sel = f"K{self.rng.randint(-1, 3)}"                # a constant selector ([LINT])
        self.op("CASE", sel)
        worst = 0
        n = self.rng.randint(1, 5)
        if self.has("case_empty") and self.chance(0.1):
            n = 0                                   # a table without entries: nothing is ever called
        plain = self.rng.randrange(n) if n and not self.has("case_empty") else -1
        for i in range(n):
            s = self.pick_sub(subs)
            worst = max(worst, s.cost)
            if i != plain and self.has("cfg") and self.chance(0.2):
                self.put(self.pp_cond())
                self.op("CM", s.name)
                self.put("#endif")
            else:
                self.op("CM", s.name)
        self.op("ENDC")
        self.cost += worst

    # index register, KF -----------------------------------------------------------------------------

    def set_x(self, mask: int) -> None:
        if self.chance(0.2):
            self.op("L", f"K{self.rng.randint(0, mask) & mask}")
        else:
            self.op("L", self.dyn_val() if self.chance(0.7) else self.val_r())
            self.op("A", f"K{mask}")
        self.op("=", "X")

    def s_index(self, ctx: _Ctx) -> None:
        r = self.rng.random()
        ext = self.has("extended")
        if r < 0.3:                                               # byte table, 0..7 (+1 with INCX)
            base = self.rng.randrange(IDX_BYTE_MAX)
            self.set_x(7 if not ext else 6)
            if ext and self.chance(0.4):
                self.op("INCX")                                   # 1..7
                if self.chance(0.4):
                    self.op("DECX")
            sym = self.sym.get(("B", base))
            self.op("L", f"{sym}[X]" if sym and self.chance(0.5) else f"B{base}[X]")
            self.word_op(x_ok=True)
            dst = self.rng.randrange(IDX_BYTE_MAX)
            self.op("=", f"B{dst}[X]")
            self.touch_bytes(dst, 8)
        elif r < 0.5:                                             # word/double tables: the index counts bytes
            kind = self.rng.choice("WD")
            mask = 6 if kind == "W" else 12
            base = self.rng.randrange(IDX_BYTE_MAX // 4) * 4
            self.set_x(mask)
            self.op("L", f"{kind}{base}[X]")
            self.word_op(x_ok=True)
            if self.has("index_wide"):
                self.op("=", f"{kind}{base}[X]")
                self.touch_bytes(base, mask + 4)
            else:
                self.op("=", self.val_w())
        elif r < 0.75:                                            # bit tables: inputs, markers, outputs
            self.set_x(7)
            ib = self.rng.randrange(N_INPUTS - 7)
            mb = M_TABLE + 10 * self.rng.randrange(9)
            src = self.rng.choice((f"I{ib}[X]", f"M{mb}[X]", f"I{ib}[X]"))
            msym = self.sym.get(("M", mb))
            self.op("L", src)
            self.op(self.rng.choice(GATES), self.bit_r())
            dst = self.rng.choice((f"{msym}[X]" if msym else f"M{mb}[X]", f"O{O_GEN + self.rng.randrange(9)}[X]"))
            self.op(self.rng.choice(("=", "S", "R")), dst)
            if self.has("bitpack"):
                base = dst.split("[")[0]
                self.op("LB", base)
                self.op("B=", base)
            else:
                self.op("L", dst)
                self.op("=", self.bit_w())
        else:                                                     # X as a word operand
            self.set_x(self.rng.choice((7, 15, 255)))
            self.op("L", self.rng.choice(("X", self.val_r())))
            mnemonic = self.rng.choice(("+", "-", "x", "<<", ">>", "A", "O", "BS", "=="))
            self.op(mnemonic, "X")
            if mnemonic == "==":
                self.assigns(1, 1)
            else:
                self.op("=", self.val_w())

    def s_kfield(self, ctx: _Ctx) -> None:
        unit = self.cur
        inline = unit.is_main and self.chance(0.2)
        if inline or not unit.kfields or self.chance(0.4):
            name = unit.fresh("Tab")
            values = [self.const_lit() for _ in range(self.rng.randint(1, 8))]
            if not inline:
                unit.kfields.append((name, values))
        else:
            name, values = self.rng.choice(unit.kfields)
        n = len(values)
        if n & (n - 1) == 0:
            self.set_x(n - 1)
        else:
            self.op("L", self.val_r())
            self.op("A", "K$FF")
            self.op("MOD", f"K{n}")
            self.op("=", "X")
        r = self.rng.random()
        if r < 0.5:
            self.op("L", f"KF {name}[X]")
            self.op("=", self.val_w())
        elif r < 0.8:
            self.op("L", self.val_r())
            self.op(self.rng.choice(("+", "-", "x", "A", "O", "XO", "MOD")), f"KF {name}[X]")
            self.op("=", self.val_w())
        else:
            self.op("L", self.val_r())
            self.op(self.rng.choice(COMPARES), f"KF {name}[X]")
            self.assigns(1, 1)
        if inline:
            skip = unit.fresh("Lb")
            self.op("JP", skip)
            self.put(f"KFIELD {name}")
            for v in values:
                self.put(v)
            self.put("ENDK")
            self.label(skip)

    # timers, counters, edges, NC --------------------------------------------------------------------

    def s_timer(self, ctx: _Ctx) -> None:
        n = self.timer_no()
        start, run = self.name("T", n), self.name("T", TIMER_RUNNING + n)
        r = self.rng.random()
        if r < 0.35:
            self.cond()
            self.op(self.rng.choice(("=", "=", "S")), start)
            self.op("L", run)
            if self.has("logic") and self.chance(0.4):
                self.op(self.rng.choice(GATES), self.bit_r())
            self.assigns(1, 1)
        elif r < 0.6:                                            # on-delay from a rising edge
            mem = self.reserve_edge()
            i = self.inp()
            self.op("L", i)
            self.op("AN", mem)
            self.op("=", start)
            self.op("L", i)
            self.op("=", mem)
            self.op("L", i)
            self.op("AN", start)
            self.op("AN", run)
            self.assigns(1, 1)
        elif r < 0.75:                                           # self-restarting blink timer
            self.op("LN", run)
            self.op("AN", start)
            self.op("=", start)
            self.op("L", run)
            self.assigns(1, 1)
        elif r < 0.9:                                            # start operand read back, reset
            self.cond()
            self.op("S", start)
            self.op("L", start)
            self.assigns(1, 1)
            if self.chance(0.3):
                self.op("L", self.bit_r())
                self.op("R", start)
        elif r < 0.96:
            self.op("L", run)
            self.op("=", self.mem("B"))
        else:                                                    # the running operand written by the program
            self.cond()
            self.op(self.rng.choice(("=", "S", "R")), run)
            self.op("L", run)
            self.assigns(1, 1)

    def s_counter(self, ctx: _Ctx) -> None:
        n = self.counter_no()
        r = self.rng.random()
        if r < 0.3:
            self.cond()
            self.op(self.rng.choice(("=", "S")), self.name("C", n))
        elif r < 0.6:
            self.cond()
            self.op(self.rng.choice(("=", "=", "S", "R")), self.name("C", COUNTER_RELEASE + n))
        elif r < 0.85:
            self.op("L", self.name("C", COUNTER_RUNNING + n))
            if self.has("logic"):
                self.gates(0, 1)
            self.assigns(1, 1)
        else:                                                   # count rising edges of an input
            mem = self.reserve_edge()
            i = self.inp()
            self.op("L", i)
            self.op("AN", mem)
            self.op("=", self.name("C", COUNTER_RELEASE + n))
            self.op("L", i)
            self.op("=", mem)
            self.op("L", self.inp())
            self.op("=", self.name("C", n))
            self.op("L", self.name("C", COUNTER_RUNNING + n))
            self.assigns(1, 1)

    def s_edge(self, ctx: _Ctx) -> None:
        mem = self.reserve_edge()
        src = self.inp() if self.chance(0.7) else self.bit_r()
        rise = self.reserve_edge() if self.chance(0.5) else self.bit_w()
        self.op("L", src)
        self.op("AN", mem)
        self.op("=", rise)
        if self.chance(0.5):
            self.op("LN", src)
            self.op("A", mem)
            self.op("=", self.bit_w())
        self.op("L", src)
        self.op("=", mem)
        r = self.rng.random()
        if r < 0.4 and self.has("struct"):
            self.op("L", rise)
            self.op("IFT")
            acc = self.mem()
            if self.has("extended") and self.chance(0.5):
                self.op("INC", acc)
            else:
                self.increment(acc)
            self.op("ENDI")
        elif r < 0.7:
            self.op("L", rise)
            self.op("XO", self.obit())
            self.op("=", self.obit())

    def s_nc(self, ctx: _Ctx) -> None:
        r = self.rng.random()
        plain = self.plain_subs(ctx)
        if r < 0.25:
            self.op("L", "M4172")
            if plain and self.chance(0.5):
                s = self.pick_sub(plain)
                self.op("CMT", s.name)
                self.cost += s.cost
            else:
                self.op(self.rng.choice(("=", "S", "R")), self.bit_w())
        elif r < 0.45:
            self.op("L", self.rng.choice(("W272", "W262", "W264", "W260", "W256")))
            self.op(self.rng.choice(COMPARES), self.rng.choice(("K-1", "K0", "K1", "K3", "K5", self.mem())))
            self.assigns(1, 1)
        elif r < 0.7:                                           # acknowledge a strobe
            strobe, ack = self.rng.choice(ACKS)
            self.op("L", f"M{strobe}")
            if self.has("brackets_logic") and self.has("compare") and strobe == 4072 and self.chance(0.5):
                self.op("A[")
                self.op("L", "W260")
                self.op("==", f"K{self.rng.randint(0, 9)}")
                self.op("]")
                self.op("S", self.obit())
                self.op("L", f"M{strobe}")
            self.op("=", f"M{ack}")
        elif r < 0.85:
            self.op("L", self.rng.choice(("D280", "D284", "D356", "W264")))
            self.op("+", self.rng.choice(("D284", "K1", self.mem())))
            self.op("=", self.val_w())
        else:
            self.op("L", "M4200")
            self.op("O", "M4201")
            self.op("O", "M4202")
            self.op("ON", "M4203")
            self.assigns(1, 1)

    # preprocessor -----------------------------------------------------------------------------------

    def pp_cond(self) -> str:
        name, value = self.rng.choice(self.defines)
        r = self.rng.random()
        if r < 0.1:
            return f"#ifdef {name}"
        if r < 0.15:
            return f"#ifndef {self.rng.choice((name, 'CFG_Missing'))}"
        if r < 0.2:
            other = self.rng.choice(self.defines)[0]
            return f"#if {name} = &{other}"
        if value.startswith('"'):
            test = self.rng.choice((value, '"abc"', '"xyz"'))
        elif value.startswith("&"):
            test = self.rng.choice((value, "1", "0"))
        elif value.startswith("%"):
            test = self.rng.choice((value, "5", "%0110", "6"))
        else:
            test = self.rng.choice((value, "0", "1", "2", "3"))
        return f"#if {name} {self.rng.choice(('=', '=', '<>'))} {test}"

    def s_cfg(self, ctx: _Ctx) -> None:
        if self.chance(0.3) and self.has("logic"):
            self.chain_start()
            self.put(self.pp_cond())
            self.op(self.rng.choice(GATES), self.bit_r())
            if self.chance(0.6):
                self.put("#else")
                self.op(self.rng.choice(GATES), self.bit_r())
            self.put("#endif")
            self.assigns(1, 1)
            return
        self.put(self.pp_cond())
        saved = self.cost
        self.body(ctx.deeper(), 1, 2)
        first = self.cost - saved
        if self.chance(0.5):
            self.put("#else")
            mark = self.cost
            self.body(ctx.deeper(), 1, 2)
            self.cost = saved + max(first, self.cost - mark)
        self.put("#endif" if self.chance(0.7) else "#endif ; cfg")

    # extended, bit packing, strings -----------------------------------------------------------------

    def s_extended(self, ctx: _Ctx) -> None:
        r = self.rng.random()
        if r < 0.3:
            self.op(self.rng.choice(("INC", "DEC")), self.val_w())
        elif r < 0.7:
            self.word_load()
            for _ in range(self.rng.randint(1, 3)):
                self.op(self.rng.choice(("INCW", "DECW", "TWOC", "NOTW")))
            self.op("=", self.val_w())
        elif r < 0.92 or not self.has("logic"):
            self.chain_start()
            self.op("NOTL")
            if self.has("logic"):
                self.gates(0, 1)
            self.assigns(1, 1)
        else:
            self.op(self.rng.choice(("INC", "DEC")), self.bit_w())   # a bit counts modulo 2

    def bit_base(self, n: int, write: bool) -> str:
        r = self.rng.random()
        if not write and r < 0.4:
            start = self.rng.randint(0, N_INPUTS - n)
            return f"I{start}"
        if r < 0.75:
            return f"M{self.rng.randint(0, M_GEN - n)}"
        if n <= 32:
            return f"O{self.rng.randint(0, O_GEN - n)}"
        return f"M{self.rng.randint(0, M_GEN - n)}"

    def s_bitpack(self, ctx: _Ctx) -> None:
        width = self.rng.choice((8, 8, 16, 16, 32))
        if self.chance(0.5):
            self.op({8: "LB", 16: "LW", 32: "LD"}[width], self.bit_base(width, False))
            if self.chance(0.5):
                self.word_op()
            self.op("=", self.val_w())
        else:
            self.word_load()
            if self.chance(0.4):
                self.word_op()
            self.op({8: "B=", 16: "W=", 32: "D="}[width], self.bit_base(width, True))

    def string_lit(self) -> str:
        r = self.rng.random()
        if r < 0.04 and self.has("strings_long"):
            return 'S"' + "".join(self.rng.choice("ABCDEFGH") for _ in range(self.rng.randint(60, 120))) + '"'
        if r < 0.6:
            return 'S"' + "".join(self.rng.choice("ABCDEF XYZ019") for _ in range(self.rng.randint(0, 8))) + '"'
        if r < 0.8 and self.strings_used:
            return f"S{self.rng.choice(sorted(self.strings_used))}"
        if r < 0.9:
            return f"S#E{self.rng.randint(0, 999)}"
        return f"S#D{self.rng.randint(0, 4095)}"

    def s_string(self, ctx: _Ctx) -> None:
        dst = self.rng.randrange(N_STRINGS)
        r = self.rng.random()
        if r < 0.5 or not self.strings_used:
            self.op("L", self.string_lit())
            for _ in range(self.rng.randint(0, 2)):
                self.op("+", self.string_lit())
            self.op("=", f"S{dst}")
            self.strings_used.add(dst)
        elif r < 0.8:
            self.op("L", f"S{self.rng.choice(sorted(self.strings_used))}")
            self.op(self.rng.choice(COMPARES), self.string_lit())
            self.assigns(1, 1)
        elif self.has("struct"):
            self.cond()
            self.op("IFT")
            self.op("L", self.string_lit())
            self.op("ELSE")
            self.op("L", self.string_lit())
            self.op("ENDI")
            self.op("=", f"S{dst}")
            self.strings_used.add(dst)
        else:
            self.op("L", self.string_lit())
            self.op("=", f"S{dst}")
            self.strings_used.add(dst)

    # odd corners ------------------------------------------------------------------------------------

    def s_main_em(self, ctx: _Ctx) -> None:
        """EMT/EMF in the main program: the rest of the cycle is skipped (rarely: about 1 cycle in 8)."""
        if self.chance(0.6):
            self.op("L", self.inp())
            self.op("A", self.inp())
            self.op("A", self.inp())
            self.op("EMT")
        else:
            self.op("L", self.inp())
            self.op("O", self.inp())
            self.op("O", self.inp())
            self.op("EMF")

    def s_carry(self, ctx: _Ctx) -> None:
        if self.chance(0.5):
            self.word_op()
            self.op("=", self.val_w())
        else:
            self.assigns(1, 1)

    def s_flow(self, ctx: _Ctx) -> None:
        """WA and LA live across labels, conditional jumps, structured statements and loops, merged afterwards."""
        unit = self.cur
        r = self.rng.random()
        if r < 0.25 and self.has("jumps"):                 # WA changed on one path only
            lbl = unit.fresh("Lb")
            self.chain_start()
            self.word_load()
            self.op(self.rng.choice(("JPF", "JPT")), lbl)
            for _ in range(self.rng.randint(1, 2)):
                self.word_op()
            if self.chance(0.3):
                self.op("L", self.bit_r())                  # ... and LA too
            self.label(lbl)
            if self.chance(0.4):
                self.word_op()
            self.op("=", self.val_w())
            if self.chance(0.5):
                self.assigns(1, 1)
        elif r < 0.45 and self.has("jumps"):               # LA changed on one path only
            lbl = unit.fresh("Lb")
            self.chain_start()
            self.op(self.rng.choice(("JPF", "JPT")), lbl)
            self.chain_start()
            self.gates(0, 1)
            self.label(lbl)
            self.gates(0, 1)
            self.assigns(1, 2)
        elif r < 0.7 and self.has("struct"):               # WA/LA through IFT/ELSE
            self.word_load()
            self.bit_cond()
            self.op(self.rng.choice(("IFT", "IFF")))
            for _ in range(self.rng.randint(0, 2)):
                self.word_op()
            if self.chance(0.4):
                self.chain_start()
            if self.chance(0.5):
                self.op("ELSE")
                for _ in range(self.rng.randint(0, 2)):
                    self.word_op()
                if self.chance(0.3):
                    self.op(self.rng.choice(("L", "LN")), self.bit_r())
            self.op("ENDI")
            self.op("=", self.val_w())
            self.assigns(1, 1)
        elif self.has("loops") and self.has("stack") and ctx.may_loop:
            # WA accumulates across the iterations of a loop; the counter test saves it on the stack
            cnt = self.reserve_word()
            n = self.rng.randint(1, 6)
            top = unit.fresh("Lp")
            self.set_zero(cnt)
            self.word_load()
            self.label(top)
            start = self.cost
            for _ in range(self.rng.randint(1, 2)):
                self.word_op()
            self.op("PSW")
            if self.has("extended") and self.chance(0.5):
                self.op("INC", cnt)
                self.op("L", cnt)
            else:
                self.increment(cnt)
            self.op("<", f"K{n}")
            self.op("PLW")
            self.op("JPT", top)
            self.charge_repeats(start, n)
            self.op("=", self.val_w())
            if self.chance(0.5):
                self.assigns(1, 1)                     # LA of the last counter test
        else:
            self.s_carry(ctx)

    def s_write_input(self, ctx: _Ctx) -> None:
        i = self.rng.randrange(20, N_INPUTS)
        self.chain_start()
        self.op("=", f"I{i}")
        self.op("L", f"I{i}")
        self.op("=", self.bit_w())

    # ---------------------------------------------------------------- faults

    def fault_block(self, unit: _Unit) -> None:
        skip = unit.fresh("Lb")
        i = self.rng.randrange(N_INPUTS)
        self.op("L", f"I{i}")
        self.op("JPF", skip)
        kind = self.rng.choice(("index", "align", "underflow", "kf", "bitindex"))
        self.put(f"; injected runtime fault: {kind}")
        if kind == "index":
            self.op("L", "K200")
            self.op("=", "X")
            self.op("L", "B9900[X]")
            self.op("=", "W2")
        elif kind == "align":
            self.op("L", "K1")
            self.op("=", "X")
            self.op("L", "W0[X]")
            self.op("=", "W2")
        elif kind == "underflow":
            self.op("PL", "D8")
        elif kind == "kf":
            self.op("L", "K3")
            self.op("=", "X")
            self.op("L", "KF FaultTab[X]")
            self.op("=", "W2")
            self.op("JP", skip)
            self.put("KFIELD FaultTab")
            self.put("K1")
            self.put("K2")
            self.put("ENDK")
        else:
            self.op("L", "K300")
            self.op("=", "X")
            self.op("L", "M9800[X]")
            self.op("=", "M2")
        self.label(skip)

    # ---------------------------------------------------------------- subprograms

    def gen_sub(self, sub: _Sub) -> None:
        unit = sub.unit
        self.cur = unit
        self.lines = []
        self.cost = 0
        ctx = _Ctx(unit, rank=sub.rank, job=sub if sub.kind == "job" else None)
        if sub.exported:
            self.put(f"GLOBAL {sub.name}")
        self.label(sub.name)
        if sub.kind in ("plain", "job"):
            n = self.rng.randint(1, 4)
            guard = self.rng.randrange(n + 1) if self.has("calls") and self.chance(0.3) else -1
            job_op = self.rng.randrange(n) if sub.kind == "job" and self.chance(0.7) else -1
            for i in range(n):
                if i == job_op:                              # RPLY, SUBM or CAN inside the job itself
                    self.job_op_in_job(ctx, sub)
                if i == guard:
                    self.cond()
                    if self.has("struct") and self.chance(0.3):
                        self.op(self.rng.choice(("IFT", "IFF")))     # an early return inside a structure
                        self.body(ctx.deeper(), 0, 1)
                        self.op("EM")
                        self.op("ENDI")
                    else:
                        self.op(self.rng.choice(("EMT", "EMF")))
                self.stmt(ctx)
        elif sub.kind == "wa":
            for _ in range(self.rng.randint(1, 3)):
                self.word_op()
            if self.chance(0.3):                      # an early return with the WA computed so far
                self.bit_cond()
                self.op(self.rng.choice(("EMT", "EMF")))
                self.word_op()
            if self.chance(0.4):
                self.op("=", self.val_w())
                self.word_op()
        elif sub.kind == "la":
            r = self.rng.random()
            if r < 0.4:
                self.assigns(1, 2)                   # uses the caller's LA
                self.op("L", self.bit_r())
                self.gates(0, 2)
            elif r < 0.7 and self.has("brackets_logic"):
                self.op(self.rng.choice(GATES) + "[")    # after LBL: mode LOGIC, chain closed -> load bracket
                self.chain_start()
                self.gates(0, 2)
                self.op("]")
                self.gates(0, 1)
            else:
                self.op(self.rng.choice(GATES), self.bit_r())   # at chain start after LBL: acts as a load
                self.gates(0, 2)
        elif sub.kind == "stack":
            params = [self.reserve_double() for _ in range(sub.params)]
            self.combine_params(params, ARITH + ("A", "O", "XO"))
            for _ in range(self.rng.randint(0, 2)):
                self.word_op()
            if self.chance(0.3):
                self.op("=", self.val_w())
            if self.chance(0.7):
                self.op("PSW")
            else:
                d = self.reserve_double()
                self.op("=", d)
                self.op("PS", d)
        else:                                       # bitstack
            params = [f"M{M_SUBPAR + self.reserved_subbits + i}" for i in range(sub.params)]
            self.reserved_subbits += sub.params
            self.combine_params(params, GATES)
            self.gates(0, 1)
            if self.chance(0.5):
                self.op("=", self.bit_w())
            self.op("PSL")
        self.op("EM")
        sub.cost = max(1, self.cost)
        sub.lines = self.lines

    def combine_params(self, params: list[str], mnemonics: tuple[str, ...]) -> None:
        """Pulls the caller's parameters off the data stack (last pushed first) and combines them in order."""
        for p in reversed(params):
            self.op("PL", p)
        self.op("L", params[0])
        for p in params[1:]:
            self.op(self.rng.choice(mnemonics), p)

    def sub_kind(self) -> str:
        kinds = [("plain", 10.0)]
        if self.has("acc_calls"):
            kinds += [("wa", 2.0), ("la", 1.5)]
        if self.has("stack_calls") and self.has("stack"):
            kinds += [("stack", 2.0), ("bitstack", 1.0)]
        return self.rng.choices([k for k, _ in kinds], [w for _, w in kinds])[0]

    # ---------------------------------------------------------------- project

    def make_defines(self) -> list[str]:
        out = ["; OEM.cfg of a generated difftest project: DEFINEs evaluated by #if in .src and .def files", ""]
        a = self.rng.randint(0, 1)
        num = self.rng.randint(0, 3)
        text = self.rng.choice(('"abc"', '"xyz"'))
        mask = self.rng.choice(("%0101", "%0110"))
        self.defines = [("CFG_A", str(a)), ("CFG_Num", str(num)), ("CFG_Text", text), ("CFG_Mask", mask),
                        ("CFG_Ref", "&CFG_A")]
        for name, value in self.defines:
            out.append(f"DEFINE {name} = {value}")
        return out

    def make_defs(self) -> None:
        lines = ["* global symbols of a generated difftest project", "#type generated"]
        taken: set[str] = set()

        def add(kind: str, addr: int, name: str, text: str | None = None) -> None:
            if name in taken or (kind, addr) in self.sym:
                return
            taken.add(name)
            self.sym[(kind, addr)] = name
            lines.append(text or f"{name:<18} {kind} {addr}")

        for _ in range(self.rng.randint(2, 5)):
            a = self.rng.randrange(N_INPUTS)
            add("I", a, f"IG_in{a}", f"IG_in{a:<13} I {a}" if self.chance(0.5) else None)
        for _ in range(self.rng.randint(1, 3)):
            a = self.rng.randrange(O_GEN)
            add("O", a, f"OG_out{a}")
        for _ in range(self.rng.randint(2, 4)):
            a = self.rng.randrange(32)
            add("M", a, f"MG_m{a}")
        mt = M_TABLE + 10 * self.rng.randrange(9)
        add("M", mt, f"MG_table{mt}")
        for kind in "BWD":
            for _ in range(self.rng.randint(0, 2)):
                size = BYTES_PER_OPERAND[kind]
                a = self.rng.randrange(64 // size) * size
                add(kind, a, f"{kind}G_v{a}")
        if self.has("timers"):
            for _ in range(self.rng.randint(0, 2)):
                n = self.timer_no()
                add("T", n, f"TS_t{n}")
                add("T", TIMER_RUNNING + n, f"TR_t{n}")
        if self.has("counters") and self.chance(0.5):
            n = self.counter_no()
            add("C", n, f"CS_c{n}")
            add("C", COUNTER_RELEASE + n, f"CD_c{n}")
            add("C", COUNTER_RUNNING + n, f"CR_c{n}")
        for k in range(self.rng.randint(1, 3)):
            name = f"KG_c{k}"
            lines.append(f"{name:<18} K {self.const_lit()[1:]}")
            self.const_syms.append(name)
        if self.has("cfg") and self.chance(0.6):
            lines.append(self.pp_cond())
            lines.append(f"{'KG_cfg':<18} K {self.rng.randint(-50, 50)}")
            lines.append("#else")
            lines.append(f"{'KG_cfg':<18} K {self.rng.randint(-50, 50)}")
            lines.append("#endif")
            self.const_syms.append("KG_cfg")
        for k in range(self.rng.randint(0, 2)):
            lines.append(f"ML_auto{k:<11} M")
            self.auto_bits.append(f"ML_auto{k}")
        for k in range(self.rng.randint(0, 2)):
            kind = self.rng.choice("BWD")
            lines.append(f"{kind}L_auto{k:<11} {kind}")
            self.auto_words.append(f"{kind}L_auto{k}")
        msyms = sorted(n for (kind, a), n in self.sym.items() if kind == "M" and a < 32)
        if msyms and self.chance(0.5):
            lines.append(f"/c MG_alias{'':<9} M &{self.rng.choice(msyms)}")
            self.auto_bits.append("MG_alias")
        self.def_lines = lines

    def generate(self) -> GeneratedProject:
        files: dict[str, str] = {}
        cfg_name = None
        if self.has("cfg"):
            files["OEM.cfg"] = "\n".join(self.make_defines()) + "\n"
            cfg_name = "OEM.cfg"
        if self.has("defs"):
            self.make_defs()
        main = _Unit("main.src", True, "Sub_")
        mods: list[_Unit] = []
        if self.has("modules") and self.has("calls") and self.chance(0.6):
            for k in range(self.rng.randint(1, 2)):
                mods.append(_Unit(f"mod{k + 1}.src", False, f"M{k + 1}_"))
            if len(mods) == 2 and self.chance(0.7):
                mods[1].uses.append(mods[0])
            main.uses.extend(mods)
        # file-local symbols of the modules (#define without /g)
        for m in mods:
            if self.has("defs") and self.chance(0.5):
                a = self.rng.randrange(32)
                if ("M", a) not in self.sym:
                    m.local_syms[("M", a)] = f"ML_{m.stem}m{a}"
                    m.local_def_lines = [f"* local symbols of {m.name}", f"ML_{m.stem}m{a:<10} M {a}"]
        # subprograms: modules first, then main; a subprogram may call only lower ranks
        rank = 0
        n_main_subs = (self.rng.randint(1, 2) + self.size // 7) if self.has("calls") else 0
        plan: list[_Sub] = []
        for m in mods:
            for k in range(self.rng.randint(1, 3)):
                plan.append(_Sub(f"{m.stem}Fn{k}", m, self.sub_kind(), 0, exported=True))
            for k in range(self.rng.randint(0, 2)):
                plan.append(_Sub(f"Priv{k}", m, "plain", 0))
        for k in range(n_main_subs):
            plan.append(_Sub(f"Sub_{k}", main, self.sub_kind(), 0))
        for s in plan:
            s.rank = rank
            rank += 1
            if s.kind in ("stack", "bitstack"):
                s.params = self.rng.randint(1, 3)
            self.gen_sub(s)
            s.unit.subs.append(s)
            self.all_subs.append(s)
        # submit jobs: subprograms of the main file that only SUBM starts; they may call every other subprogram
        if self.has("submit") and self.has("calls") and self.chance(0.6):
            self.jobs = [_Sub(f"Job_{k}", main, "job", 0, ident=self.reserve_word())
                         for k in range(self.rng.randint(1, 3))]
            for s in self.jobs:
                s.rank = rank
                rank += 1
                self.gen_sub(s)
                main.subs.append(s)
        # the main program
        self.cur = main
        blocks: list[list[str]] = []
        ctx = _Ctx(main, rank=10 ** 6, top=True)
        n_blocks = self.size
        fault_at = self.rng.randrange(n_blocks) if self.faults else -1
        seeds = min(max(2, n_blocks // 10), n_blocks) if self.has("word") else 0
        for b in range(n_blocks):
            self.lines = []
            self.cost = 0
            if b == 0 and self.has("acc_carry") and self.chance(0.15):
                self.s_carry(ctx)                     # WA/LA as the previous cycle left them (8.1 phase 4)
            elif b < seeds:
                self.s_accumulate(ctx)
            else:
                self.stmt(ctx)
            if b == fault_at:
                self.fault_block(main)
            blocks.append(self.lines)
        if self.has("calls"):                         # one more block for each subprogram nobody calls yet
            for s in self.callable_subs(ctx):
                if s.calls == 0:
                    self.lines = []
                    s.calls += 1
                    self.call_sub(ctx, s)
                    blocks.append(self.lines)
        for s in self.jobs:                           # and for each job nobody submits yet
            if s.calls == 0:
                self.lines = []
                self.guarded(lambda: self.submit_job(s))
                blocks.append(self.lines)
        # main.src
        out = [f"; generated by tests/difftest/generator.py, seed {self.seed}, size {self.size}"]
        if self.def_lines:
            out.append("#define /g defs.def")
        for m in mods:
            out.append(f"USES {m.name}")
        for m in mods:
            out.extend(self.externs(m))
        for b in blocks:
            out.append("; @block")
            out.extend(b)
        out.append("EM")
        out.extend(self.tail(main))
        files["main.src"] = "\n".join(out) + "\n"
        for m in mods:
            mo = [f"; module {m.name} of a generated difftest project, seed {self.seed}"]
            if m.local_def_lines:
                mo.append(f"#define {m.stem.lower()}local.def")
                files[f"{m.stem.lower()}local.def"] = "\n".join(m.local_def_lines) + "\n"
            for u in m.uses:
                mo.append(f"USES {u.name}")
                mo.extend(self.externs(u))
            mo.extend(self.tail(m))
            files[m.name] = "\n".join(mo) + "\n"
        if self.def_lines:
            files["defs.def"] = "\n".join(self.def_lines) + "\n"
        mp_name = None
        if self.timers or self.counters:
            mp = ["; timer (MP4110.n, seconds) and counter (MP4120.n, cycles) presets"]
            for n in sorted(self.timers):
                mp.append(f"MP4110.{n} : {self.timers[n]}")
            for n in sorted(self.counters):
                mp.append(f"MP4120.{n} : {self.counters[n]}")
            files["timers.mp"] = "\n".join(mp) + "\n"
            mp_name = "timers.mp"
        files["scenario.yaml"] = self.scenario(mp_name)
        return GeneratedProject(self.seed, files, "main.src", cfg_name, mp_name)

    def externs(self, used: _Unit) -> list[str]:
        return [f"EXTERN {s.name}" for s in used.subs if s.exported]

    def tail(self, unit: _Unit) -> list[str]:
        out: list[str] = []
        for s in unit.subs:
            out.append("; @block")
            out.extend(s.lines)
        for name, values in unit.kfields:
            out.append("; @block")
            out.append(f"KFIELD {name}")
            out.extend(values)
            out.append("ENDK")
        return out

    def scenario(self, mp_name: str | None) -> str:
        lines = [f"name: difftest_seed{self.seed}", "cycles: 300"]
        if mp_name:
            lines.append(f"machine_parameters: {mp_name}")
        lines.append("random:")
        lines.append(f"  seed: {self.seed}")
        lines.append(f"  inputs: [{', '.join(f'I{i}' for i in range(N_INPUTS))}]")
        lines.append("  toggle_probability: 0.1")
        if self.has("nc"):
            lines.append("events:")
            cycle = 5
            for _ in range(self.rng.randint(1, 4)):
                action = self.rng.choice(("{m_function: 3}", "{m_function: 5}", "{tool_call: {tool: 5, pocket: 2}}",
                                          "{gear: 2}", "{spindle_speed: 1500}", "{tool_def: {tool: 7, pocket: 4}}",
                                          "{fn19: {value1: 10, value2: -3}}", "{restart: program}",
                                          "{restart: machine_parameters}", "{mode: 5}"))
                lines.append(f"  - {{cycle: {cycle}, nc: {action}}}")
                cycle += self.rng.randint(5, 40)
        return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------------------
# public entry points


def generate(seed: int, *, size: int = 40, faults: bool = False, features: Iterable[str] | None = None,
             enable: Iterable[str] = (), disable: Iterable[str] = ()) -> GeneratedProject:
    """A random, well-defined project; the same arguments give byte-identical files.

    features: the full feature set (default: default_features()); enable/disable adjust it.
    """
    chosen = frozenset(features) if features is not None else default_features()
    enable, disable = frozenset(enable), frozenset(disable)
    unknown = sorted((chosen | enable | disable) - frozenset(FEATURES))
    chosen = (chosen | enable) - disable
    if unknown:
        raise ValueError(f"unknown feature(s): {', '.join(unknown)}")
    return _Gen(seed, size, chosen, faults).generate()


def _feature_list(text: str) -> list[str]:
    return [name.strip() for name in text.split(",") if name.strip()]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m tests.difftest.generator", description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int)
    p.add_argument("--size", type=int, default=40)
    p.add_argument("--faults", action="store_true", help="inject exactly one runtime fault")
    p.add_argument("--disable", default="", help="comma-separated features to switch off")
    p.add_argument("--enable", default="", help="comma-separated features to switch on")
    p.add_argument("--list-features", action="store_true")
    p.add_argument("--out", type=Path)
    args = p.parse_args(argv)
    if args.list_features:
        for name, text in FEATURES.items():
            flag = " (off: known divergence)" if name in KNOWN_DIVERGENT else ""
            print(f"{name:<15} {text}{flag}")
        return 0
    if args.seed is None or args.out is None:
        p.error("--seed N and --out DIR are required")
    project = generate(args.seed, size=args.size, faults=args.faults, enable=_feature_list(args.enable),
                       disable=_feature_list(args.disable))
    path = project.write(args.out)
    extra = f" --cfg {args.out / project.cfg}" if project.cfg else ""
    print(f"{path}{extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
