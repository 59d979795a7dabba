"""Diagnostics: source spans, the registry of diagnostic codes, and the collector every stage reports into."""

from __future__ import annotations

import dataclasses
import enum
from typing import Iterable

from transpiler.records import builder, quick_init


class Severity(enum.Enum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


@quick_init
@dataclasses.dataclass(frozen=True, order=True, slots=True)
class Span:
    """A position in an original source file (1-based line and column)."""

    file: str
    line: int
    col: int = 1
    end_line: int = 0
    end_col: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


NO_SPAN = Span("<command line>", 1, 1)
new_span = builder(Span)        # Span(...) for the preprocessor's loop over the lines


@dataclasses.dataclass(frozen=True)
class CodeInfo:
    """What a diagnostic code means, its severity, and a small example that triggers it.

    The severity here is the only one a code ever has: call sites report a code, never a
    severity. `allowable` errors may be turned into warnings by an explicit user choice
    (e.g. `--allow-untranslated`); no other error can.
    """

    code: str
    severity: Severity
    summary: str
    example: str = ""
    allowable: bool = False


def _c(code: str, sev: str, summary: str, example: str = "", *, allowable: bool = False) -> CodeInfo:
    return CodeInfo(code, Severity(sev), summary, example, allowable)


# The one registry of diagnostic codes (the language's and the tool's own).
CODES: dict[str, CodeInfo] = {
    info.code: info
    for info in (
        # preprocessor and configuration
        _c("E-PP-NEST", "error", "unbalanced #if/#else/#endif", "#if A = 1\nL I1\n; missing #endif"),
        _c("E-PP-UNDEF", "warning", "#if tests a DEFINE name that is not defined (compares as the empty string)",
           '#if CFG_NOT_SET = "x"\n#endif'),
        _c("E-PP-UNDEF-REF", "warning", "&name refers to an undefined DEFINE; it evaluates to the string \"name\"",
           "DEFINE A = &undefined_name"),
        _c("E-PP-SYNTAX", "error", "malformed preprocessor directive", "#if = 3"),
        _c("E-DEF-REDEFINE", "warning", "a DEFINE is defined again; the later value wins", "DEFINE A = 1\nDEFINE A = 2"),
        _c("E-CFG-SYNTAX", "error", "malformed configuration line: a DEFINE value that is not a string, integer, %binary, $hex or &name",
           "DEFINE A = 1.5"),
        _c("E-CFG-IGNORED", "warning", "a configuration line that is neither a DEFINE nor a directive is ignored",
           "this line is free text"),
        _c("E-MP-VALUE", "error", "malformed machine-parameter line or value", "MP4110.0 : fast"),
        _c("E-MP-AMBIGUOUS", "error", "more than one machine-parameter file beside the main program: name the one "
           "the translation is made with (--mp)", "; Main.src beside MP_mill.mp and MP_lathe.mp"),
        _c("E-MP-TRANSLATION", "error", "the translated program's machine-parameter values (the initial values of its "
           "preset variables) differ from the project's machine parameters: the ST was made without the project's MP "
           "file or from another one; co-simulation refuses it whatever the scenario sets",
           "; project.st made without --mp, then `hh2iec equiv Main.src --st project.st` beside MP_mill.mp"),
        _c("E-MP-UNREPRESENTABLE", "error", "a scenario's machine data (machine parameters, data-table rows) that the "
           "emitted ST cannot hold, so it cannot be written into the translated program: the run gives NO VERDICT",
           'mp: {"4110.0": 50000000}     # 2.5e9 cycles: more than a DINT preset holds'),
        _c("E-MP-NONE", "warning", "the program uses timers or counters but no machine-parameter file was found: "
           "every preset is 0 in the translation", "; Main.src uses T0, and no *.mp file is beside it"),
        # PLC data tables (MP_Data.tab, MP_Config.tab)
        _c("E-TAB-SYNTAX", "error", "malformed PLC data table: no BEGIN line, column header or [END], an unknown "
           "column, a row without NAME or VALUE, a row number that is not a whole number",
           "BEGIN MP_DATA.TAB\nNR NAME VALUE\n0  DG_x\n; no [END]"),
        _c("E-TAB-SYMBOL", "error", "a data-table row names a symbol the .def files do not define, or one that is "
           "not a marker, byte, word, double word or string", "0  DG_TC_pos_X_manul  1000"),
        _c("E-TAB-VALUE", "error", "a data-table value does not fit its operand (a marker 0/1, a byte, word or "
           "double word in its width, a string in quotes and within the string length)", "0  MG_option  2"),
        _c("E-TAB-DUP", "error", "two data-table rows set the same symbol, or two rows of a table share a row number",
           "0  DG_x  1\n1  DG_x  2"),
        # files
        _c("E-FILE-NOT-FOUND", "error", "a file named by the command line, USES, #define or INCLUDE does not exist",
           "USES missing_module.src"),
        _c("E-FILE-ESCAPE", "error", "a file path leaves the project folders (.., absolute path or symlink)",
           "USES ../outside.src"),
        _c("E-FILE-READ", "error", "a file could not be read",
           "#define /g Locked.def   ; exists, but the file cannot be read (permissions)"),
        _c("E-FILE-INCLUDE-CYCLE", "error", "a file includes itself (directly or indirectly)", 'INCLUDE "self.src"'),
        # lexical and syntax
        _c("E-SYNTAX", "error", "the line is not a valid instruction, directive or definition", "L I1 I2"),
        _c("E-UNSUPPORTED", "error", "a construct that hh2iec does not support (first word is no mnemonic, directive or label; "
           "structured symbols; code the ST back end cannot translate, which `--allow-untranslated` accepts with a warning)",
           "ERROR_MACRO 12", allowable=True),
        _c("E-LIT-RANGE", "error", "a literal does not fit in 32 bits", "L K4294967296"),
        _c("E-MOD-UNREACHABLE", "warning", "executable statement in a module file before its first LBL (never executed)",
           "GLOBAL Fn\nL I1\nLBL Fn\nEM"),
        # operands and addresses
        _c("E-OPERAND-KIND", "error", "the operand kind is not allowed for this instruction", "L K5\n= K6"),
        _c("E-ADDR-RANGE", "error", "operand address outside the profile's range", "L M99999"),
        _c("E-ADDR-ALIGN", "error", "W address not even or D address not a multiple of 4", "L W3"),
        # symbols and labels
        _c("E-SYM-UNDEF", "error", "unknown symbol", "L I_not_defined"),
        _c("E-SYM-RESERVED", "error", "a .def symbol name is literal operand syntax", "M12 M"),
        _c("E-SYM-DUP", "error", "a symbol is defined twice with different meanings", "A_x M 1\nA_x M 2"),
        _c("E-SYM-CASE", "warning", "two symbols or labels differ only in case (IEC names are case-insensitive)",
           "MG_a M 1\nMG_A M 2"),
        _c("E-SYM-DUP-LABEL", "error", "a label is defined twice in one file", "LBL A\nEM\nLBL A\nEM"),
        _c("E-SYM-GLOBAL-UNDEF", "error", "GLOBAL names a label that the file does not define", "GLOBAL Fn"),
        _c("E-SYM-UNRESOLVED", "error", "a called label is neither in the file nor imported with EXTERN from a GLOBAL export",
           "CM Fn_in_other_file"),
        _c("E-SYM-DUP-GLOBAL", "error", "two files export the same label with GLOBAL",
           "; a.src\nGLOBAL Fn\nLBL Fn\nEM\n; b.src\nGLOBAL Fn\nLBL Fn\nEM"),
        _c("E-DEF-DUP-ADDR", "warning", "two symbols name the same operand without /c", "I_a I 5\nI_b I 5"),
        _c("E-DEF-ALIAS", "error", "an & alias names an unknown symbol or one of another kind", "M_x M &I_y"),
        _c("E-DEF-POOL", "error", "no free operand left for an auto-assigned symbol",
           "; a .def file with more auto-assigned symbols than free operands of the kind\nSL_text_1 S\nSL_text_2 S\n; ... (S0-S99 all in use)"),
        # structure
        _c("E-BRACKET-DEPTH", "error", "brackets nested deeper than 16",
           "L   I1\nA[          ; 17 opening brackets in a row\nA[\n; ...\nL   I2\n]           ; and 17 closing ones"),
        _c("E-BRACKET-BALANCE", "error", "unbalanced bracket", "L I1\nA[\nL I2\nEM"),
        _c("E-BRACKET-MODE", "error", "bracket in the wrong accumulator mode (string, or arithmetic/compare after a logic instruction)",
           "L I1\n+[\nL K1\n]"),
        _c("E-BRACKET-SPAN", "error", "label, jump, call, EM, CASE or structured keyword inside a bracket", "L I1\nA[\nJP X\n]"),
        _c("E-STRUCT-NEST", "error", "structured statements (IFT/IFF/ELSE/ENDI, WHILE/ENDW, REPEAT/UNTIL) do not nest properly",
           "ELSE"),
        _c("E-CASE-BODY", "error", "something other than CM label inside CASE ... ENDC", "CASE B0\nL I1\nENDC"),
        _c("E-KF-PLACEMENT", "error", "KFIELD not directly after an unconditional EM or JP", "L I1\nKFIELD T\nK1\nENDK"),
        _c("E-JUMP-SCOPE", "error", "jump to a label of another file or an unknown label", "JP Nowhere"),
        _c("E-FALL-OFF-END", "error", "a path reaches the end of the file without EM", "L I1\n= O1"),
        _c("E-CALL-RECURSION", "error", "recursive subprogram calls", "LBL A\nCM A\nEM"),
        _c("E-CALL-DEPTH", "error", "static call depth exceeds the limit",
           "CM  F1\nEM\nLBL F1\nCM  F2\nEM\n; ... F2 calls F3, ..., F32 calls F33: 33 levels"),
        _c("E-MODULE-UNKNOWN", "error", "a PLC module number the module table does not have (for this profile); the "
           "message names the nearest known numbers (docs/modules.md)", "CM 9999"),
        # lints
        _c("W-LINT", "warning", "the program depends on a corner of the semantics that is legal but easy to misread", "L I1\n= O1\nA I2"),
        # screen masks
        _c("E-MASK-SYNTAX", "error", "a screen mask (.msk, .a) statement is malformed (docs/masks.md)",
           '"DIAG TOOL CHANGE\\n"     /* the closing semicolon is missing */'),
        _c("E-MASK-UNDEF", "error", "a screen mask names a symbol the project does not define (the message names the "
           "nearest ones), or a reference that is neither $SYMBOL$ nor an operand", '" %4D\\n", $WG_tc_stauts$/c;'),
        _c("E-MASK-FORMAT", "error", "a screen mask's format does not suit its references: %s of a number, %d of a "
           "string, /n=k without an F format, a constant, or more or fewer references than fields",
           '" %s\\n", $WG_tc_status$/c;     /* WG_tc_status is a word */'),
        # runtime (interpreter)
        _c("E-RT-STACK-OVERFLOW", "error", "data stack overflow",
           "LBL Fill\nPS  K1      ; two 16-bit words per push: the 129th overflows 256 words\nJP  Fill"),
        _c("E-RT-STACK-UNDERFLOW", "error", "data stack underflow", "PL D0\nEM"),
        _c("E-RT-INDEX", "error", "indexed operand or KF index out of range",
           "L   K200\n=   X\nL   M9900[X]   ; M10100 does not exist\n=   O1\nEM"),
        _c("E-RT-ALIGN", "error", "indexed W/D address misaligned",
           "L   K1\n=   X\nL   W0[X]      ; W1 is not an even address\n=   W2\nEM"),
        _c("E-RT-CALL-DEPTH", "error", "call depth exceeded at run time",
           "; more nested calls at run time than call_depth allows (also E-CALL-DEPTH at compile time)\nCM  F1\nEM\nLBL F1\nCM  F2\nEM\n; ..."),
        _c("E-RT-WATCHDOG", "error", "instruction budget of one cycle exceeded", "LBL L\nJP L"),
        _c("E-RT-STRING", "warning", "string result longer than 128 characters (truncated)",
           "L   S\"...100 characters...\"\n+   S\"...another 100 characters...\"   ; 200 > 128\n=   S0\nEM"),
        _c("E-RT-MODULE", "warning", "PLC module without simulation model ran as a stub (A-46)",
           "CM  9148    ; a module without a simulation model\nEM"),
        _c("E-RT-SHIFT", "error", "shift count outside 0..31 with shift_semantics = fault (A-14)",
           "L   K1\n<<  K40     ; with -S shift_semantics=fault\nEM"),
        _c("E-RT-STACK-LEFTOVER", "warning", "data stack not empty at the end of a cycle", "PS K1\nEM"),
        _c("E-SIM-HANDSHAKE-TIMEOUT", "error", "the PLC did not acknowledge an NC strobe within 10 s",
           "; scenario: nc: [{cycle: 0, m_function: 3}]\n; program: never sets the acknowledgement M4092\nEM"),
        # scenarios and tool
        _c("E-SCENARIO", "error", "malformed scenario file (unknown key, unknown name, value out of range)", "cycles: -1"),
        _c("E-SCENARIO-UNUSED", "warning", "a scenario pattern has no effect: it matches no name, or only aliases, constants "
           "or non-bit operands that are never toggled", "random:\n  inputs: [NO_SUCH_*]"),
        _c("E-ST-PARSE", "error", "the ST file could not be parsed by the built-in ST executor",
           "hh2iec equiv Main.src --st broken.st\n; broken.st:  PROGRAM P  x := ;  END_PROGRAM"),
        _c("E-TOOL", "error", "internal tool error or missing tool (a bug in hh2iec or a missing dependency)",
           "hh2iec equiv Main.src --backend matiec   ; iec2c is not installed"),
        _c("E-TARGET", "error", "the ST does not fit the chosen target's own build (for --target openplc: the "
           "configuration's names, writes through a VAR_EXTERNAL FB instance, located addresses the runtime does not "
           "map); in a translation this is a bug in hh2iec", "CONFIGURATION HH_Config  ; the OpenPLC runtime needs "
           "Config0"),
        _c("E-SHARD", "error", "shard results or a plan file that do not belong together: another command, other "
           "inputs (sources, scenarios, settings, hh2iec version), a shard missing or given twice",
           "hh2iec merge shard1.json shard2.json   ; written with --shard 1/3 and 2/3: shard 3/3 is missing"),
        _c("E-USAGE", "error", "bad command-line usage",
           "hh2iec check          ; MAIN.src is missing\nhh2iec check Main.src -D CFG_X    ; -D needs NAME=VALUE"),
        _c("E-XSD", "error", "emitted PLCopen XML does not validate against the TC6 schema (a bug in hh2iec)",
           "; a bug in hh2iec: the written project.xml does not validate against PLCopen TC6 XML v2.01"),
        # issue 20: the project as users have it, and strictness
        _c("E-PP-CASE", "warning", "a DEFINE name is used with another spelling than its definition (names compare "
           "ignoring case, A-61)", 'DEFINE CFG_panel = "active"\n#if CFG_Panel = "active"\n#endif'),
        _c("E-CFG-MISSING", "error", "#if lines test DEFINE names that nothing defines, and there is no OEM.cfg beside "
           "the main program and no --cfg", '; no OEM.cfg beside Main.src\n#if CFG_Spindle = "belt"\n#endif'),
        _c("E-DEF-UNUSED", "warning", "-D names a DEFINE that no file defines or tests (a misspelling?)",
           "hh2iec check Main.src -D CFG_Spindel=belt"),
        _c("E-WERROR", "error", "warnings were reported and --werror makes them fail the run",
           "hh2iec check Main.src --werror   ; Main.src has an E-PP-UNDEF warning"),
        _c("E-MAIN-MODULE", "error", "the file given as main program is a module (it exports labels with GLOBAL); "
           "give the main program that USES it", "hh2iec check Module.src   ; Module.src: GLOBAL Fn\nLBL Fn\nEM"),
        _c("E-ENCODING", "error", "a file is not valid text in the encoding forced with --encoding",
           "hh2iec check Main.src --encoding utf-8   ; Main.src holds the cp1252 byte 0xE4"),
    )
}


@dataclasses.dataclass(frozen=True)
class Diagnostic:
    code: str
    severity: Severity
    span: Span
    message: str
    notes: tuple[str, ...] = ()

    @classmethod
    def of(cls, code: str, span: Span, message: str, *notes: str) -> "Diagnostic":
        """A diagnostic with the severity the registry gives `code`."""
        info = CODES.get(code)
        if info is None:
            raise KeyError(f"unregistered diagnostic code {code}")
        return cls(code, info.severity, span, message, tuple(notes))

    def render(self) -> str:
        text = f"{self.span}: {self.severity.value}[{self.code}]: {self.message}"
        for note in self.notes:
            text += f"\n  note: {note}"
        return text


class CompileFailed(Exception):
    """Raised by a stage that cannot continue; carries every diagnostic collected so far."""

    def __init__(self, diagnostics: Iterable[Diagnostic]):
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(d.render() for d in self.diagnostics))


class Diagnostics:
    """Collects diagnostics of one run; suppresses exact duplicates so that one fault yields one message.

    `allowed` names error codes the user explicitly accepted (each must be registered as
    allowable): they are collected as warnings.
    """

    def __init__(self, warnings_as_errors: bool = False, allowed: Iterable[str] = ()) -> None:
        self._items: list[Diagnostic] = []
        self._seen: set[tuple[str, Span, str]] = set()
        self.warnings_as_errors = warnings_as_errors
        self.allowed = frozenset(allowed)
        for code in self.allowed:
            if not CODES[code].allowable:
                raise ValueError(f"{code} is not an error a user may allow")

    def report(self, code: str, span: Span, message: str, *notes: str) -> None:
        """Collect `code` at `span` with the severity the registry gives it."""
        self._add(Diagnostic.of(code, span, message, *notes))

    def extend(self, items: Iterable[Diagnostic]) -> None:
        for d in items:
            self._add(d)

    def _add(self, diag: Diagnostic) -> None:
        key = (diag.code, diag.span, diag.message)
        if key in self._seen:
            return
        self._seen.add(key)
        if diag.severity is Severity.ERROR and diag.code in self.allowed:
            diag = dataclasses.replace(diag, severity=Severity.WARNING)
        self._items.append(diag)

    @property
    def items(self) -> list[Diagnostic]:
        return sorted(self._items, key=lambda d: (d.span.file, d.span.line, d.span.col, d.code))

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity is Severity.ERROR]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.items if d.severity is Severity.WARNING]

    def has_errors(self) -> bool:
        return any(d.severity is Severity.ERROR for d in self._items)

    def raise_if_errors(self) -> None:
        if self.has_errors():
            raise CompileFailed(self.items)


def explain(code: str) -> str | None:
    """Text for `hh2iec explain CODE`: meaning, severity and a small failing example."""
    info = CODES.get(code.upper())
    if info is None:
        return None
    text = f"{info.code} ({info.severity.value}): {info.summary}\n"
    if info.example:
        text += "\nExample:\n" + "".join(f"    {line}\n" for line in info.example.splitlines())
    return text
