"""What the OpenPLC v3 runtime's program build needs of an ST file beyond what matiec accepts: checked on the text.

The runtime builds an uploaded program with its own matiec fork (`iec2c -f -l -p -r -R -a`), moves the files iec2c
wrote under fixed names, compiles them as C++ against its own `core/lib`, and maps located variables into its I/O
image with its glue generator. These pass matiec and still break that build, or the program on it:

- The generated files must be `Config0.c` and `Res0.c`: one CONFIGURATION `Config0` with one RESOURCE `Res0`.
- The runtime's accessor macro for writing through an FB instance reached by VAR_EXTERNAL takes fewer arguments
  than the C iec2c writes for a call with arguments of such an instance (`ext(IN := x)`): it does not compile.
  (An assignment to a member, `ext.IN := x`, and a call without arguments do.)
- The runtime's own libraries declare variables (INIT, SEND, ...) that matiec cannot read once a POU of the
  program has taken the name.
- Only some located addresses reach the I/O image (1024 entries per kind): `%IX`/`%QX` a.b with b < 8, `%IB`,
  `%QB`, `%IW`, `%QW`, `%ID`, `%QD`, `%IL`, `%MW`, `%MD`, `%ML`. `%MX` and `%MB` are not mapped at all, and `%QL`
  lands in the input table. An address past the image still builds, but the glue writes past its tables.

tests/data/openplc_verdicts records the runtime build's own verdict on a corpus of small files; these rules must
reject every file it rejects (tests/test_openplc_runtime.py).
"""

from __future__ import annotations

import re
from typing import Iterable, Iterator

from transpiler.backends.st.names import LIBRARY_VARIABLE_NAMES
from transpiler.diagnostics import Diagnostic, Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.errors import StError
from transpiler.exec.stexec.parser import parse

CONFIGURATION_NAME, RESOURCE_NAME = "Config0", "Res0"
IMAGE_ENTRIES = 1024
# Address kinds the glue generator maps (area, size): everything else never reaches the I/O image.
MAPPED = frozenset({("I", "X"), ("Q", "X"), ("I", "B"), ("Q", "B"), ("I", "W"), ("Q", "W"), ("I", "D"), ("Q", "D"),
                    ("I", "L"), ("M", "W"), ("M", "D"), ("M", "L")})
# The IEC standard function blocks: an instance of one is an FB instance as much as one of the file's own blocks.
STANDARD_FBS = frozenset({"TON", "TOF", "TP", "CTU", "CTD", "CTUD", "CTU_DINT", "CTD_DINT", "CTUD_DINT", "CTU_LINT",
                          "CTD_LINT", "CTUD_LINT", "CTU_UDINT", "CTD_UDINT", "CTUD_UDINT", "CTU_ULINT", "CTD_ULINT",
                          "CTUD_ULINT", "R_TRIG", "F_TRIG", "SR", "RS", "SEMA", "RTC", "INTEGRAL", "DERIVATIVE",
                          "PID", "RAMP", "HYSTERESIS"})
_ADDRESS = re.compile(r"%([IQM])([XBWDL]?)(\d+)(?:\.(\d+))?$", re.IGNORECASE)


def _problem(span: Span, message: str) -> Diagnostic:
    return Diagnostic.of("E-TARGET", span, message)


def openplc_problems(text: str, filename: str = "project.st") -> list[Diagnostic]:
    """Every place of `text` that the OpenPLC v3 runtime's program build rejects or cannot map (empty: it builds as
    far as these rules see); a file that does not parse gives its parse errors."""
    try:
        source = parse(text, filename)
    except StError as exc:
        return list(exc.diagnostics)
    fb_types = STANDARD_FBS | {el.name.upper() for el in source.elements
                               if isinstance(el, n.Pou) and el.kind == "function_block"}
    problems = _configuration_problems(source)
    for el in source.elements:
        if isinstance(el, n.Pou):
            problems += _external_fb_writes(el, fb_types)
            if el.name.upper() in LIBRARY_VARIABLE_NAMES:
                problems.append(_problem(el.span, f"the POU {el.name} takes a name that a library of the runtime "
                                                  "declares as a variable: that library no longer parses"))
    problems += _location_problems(source)
    return sorted(problems, key=lambda d: (d.span.line, d.span.col))


def _configuration_problems(source: n.SourceFile) -> list[Diagnostic]:
    configs = [el for el in source.elements if isinstance(el, n.Configuration)]
    if len(configs) != 1:
        return [_problem(Span(source.filename, 1, 1), f"the runtime builds exactly one CONFIGURATION, named "
                                                      f"{CONFIGURATION_NAME}; the file has {len(configs)}")]
    config = configs[0]
    problems = []
    if config.name != CONFIGURATION_NAME:
        problems.append(_problem(config.span, f"the CONFIGURATION must be named {CONFIGURATION_NAME} (the runtime "
                                              f"takes the file {CONFIGURATION_NAME}.c), not {config.name}"))
    if len(config.resources) != 1 or config.resources[0].name != RESOURCE_NAME:
        names = ", ".join(r.name for r in config.resources) or "none"
        problems.append(_problem(config.span, f"the CONFIGURATION must hold one RESOURCE named {RESOURCE_NAME} (the "
                                              f"runtime takes the file {RESOURCE_NAME}.c), not: {names}"))
    return problems


def _external_fb_writes(pou: n.Pou, fb_types: frozenset[str]) -> list[Diagnostic]:
    external = {name.upper() for block in pou.blocks if block.kind == "external" for decl in block.decls
                if isinstance(decl.spec, n.NamedTypeSpec) and decl.spec.name.upper() in fb_types
                for name, _ in decl.names}
    if not external:
        return []
    problems = []
    for stmt in _statements(pou.body):
        if isinstance(stmt, n.CallStmt) and stmt.name.upper() in external and stmt.args:
            problems.append(_problem(stmt.span, f"{pou.name} calls {stmt.name}, an FB instance it reaches through "
                                                f"VAR_EXTERNAL, with arguments: the runtime's C cannot write them"))
    return problems


def _statements(body: Iterable[n.Stmt]) -> Iterator[n.Stmt]:
    for stmt in body:
        yield stmt
        if isinstance(stmt, n.If):
            for _, branch in stmt.branches:
                yield from _statements(branch)
            yield from _statements(stmt.orelse or [])
        elif isinstance(stmt, n.Case):
            for _, branch in stmt.elems:
                yield from _statements(branch)
            yield from _statements(stmt.orelse or [])
        elif isinstance(stmt, (n.For, n.While, n.Repeat)):
            yield from _statements(stmt.body)


def _blocks(source: n.SourceFile) -> Iterator[n.VarBlock]:
    for el in source.elements:
        if isinstance(el, n.Pou):
            yield from el.blocks
        elif isinstance(el, n.GlobalBlock):
            yield el.block
        elif isinstance(el, n.Configuration):
            yield from el.globals
            for resource in el.resources:
                yield from resource.globals


def _location_problems(source: n.SourceFile) -> list[Diagnostic]:
    problems = []
    for block in _blocks(source):
        for decl in block.decls:
            if decl.location is not None:
                message = location_problem(decl.location)
                if message is not None:
                    problems.append(_problem(decl.span, f"{decl.names[0][0]} AT {decl.location}: {message}"))
    return problems


def location_problem(address: str) -> str | None:
    """Why the runtime's I/O image does not hold `address` (`%IX3.1`), or None when it does."""
    match = _ADDRESS.match(address.strip())
    if match is None:
        return "the runtime maps only one- or two-part addresses (%IX0.1, %QW3)"
    area, size, first, bit = match.group(1).upper(), (match.group(2) or "X").upper(), int(match.group(3)), match.group(4)
    if (area, size) not in MAPPED:
        return f"the runtime does not map %{area}{size} addresses into its I/O image"
    if (size == "X") != (bit is not None):
        return "a bit address needs a byte and a bit (%IX0.1), a word address has no bit part"
    if first >= IMAGE_ENTRIES:
        return f"past the runtime's I/O image ({IMAGE_ENTRIES} entries)"
    if bit is not None and int(bit) >= 8:
        return "the bit number of a %IX/%QX address is 0..7"
    return None
