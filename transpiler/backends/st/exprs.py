"""Typed ST expressions with value ranges and variable dependencies, built while the accumulators are executed symbolically."""

from __future__ import annotations

import dataclasses
import re
from types import MappingProxyType

from transpiler.backends.st.dialect import GVL_NAMES

INT32 = (-(2 ** 31), 2 ** 31 - 1)
RANGES = MappingProxyType({"SINT": (-128, 127), "INT": (-32768, 32767), "DINT": INT32, "BOOL": (0, 1)})

# Operator precedence of IEC 61131-3 ST (higher binds tighter).
PREC_ATOM, PREC_UNARY, PREC_MUL, PREC_ADD, PREC_CMP, PREC_EQ, PREC_AND, PREC_XOR, PREC_OR = 10, 9, 8, 7, 6, 5, 4, 3, 2


@dataclasses.dataclass(frozen=True, init=False)
class Expr:
    """ST text of a value, its IEC type, the variables it reads, and (for integers) its value range.

    `parts` is what the constructors below joined into the text: the function or operator word and the operand
    expressions (a tree of them); `names_of` walks it for the names the text holds, so that the clean-up passes
    and the VAR_EXTERNAL declarations look names up instead of scanning printed text. A variable's names come from
    its reference; an expression made from text alone (no parts, no variable) is read from its text. `names` keeps
    the answer once asked."""

    text: str
    typ: str
    deps: frozenset[str] = frozenset()
    lo: int = None  # type: ignore[assignment]  # None: the whole range of `typ` (set in __init__)
    hi: int = None  # type: ignore[assignment]
    prec: int = PREC_ATOM
    var: str | None = None          # set when the expression is exactly one variable (an lvalue)
    const: int | None = None        # set for integer literals
    bool_const: bool | None = None  # set for TRUE/FALSE
    parts: tuple[str | Expr, ...] | None = dataclasses.field(default=None, compare=False, repr=False)
    names: frozenset[str] | None = dataclasses.field(default=None, compare=False, repr=False)

    def __init__(self, text: str, typ: str, deps: frozenset[str] = frozenset(), lo: int | None = None,
                 hi: int | None = None, prec: int = PREC_ATOM, var: str | None = None, const: int | None = None,
                 bool_const: bool | None = None, parts: tuple[str | Expr, ...] | None = None,
                 names: frozenset[str] | None = None) -> None:
        # Written out (the back end builds tens of thousands of expressions): the fields go into the instance dict
        # as records.quick_init stores them, the range defaults with them.
        # An integer expression built without a range may hold any value of its type: assuming less would let
        # range-based simplifications (overflow checks left out) go wrong.
        if lo is None or hi is None:
            full = RANGES.get(typ, (0, 0))
            lo = full[0] if lo is None else lo
            hi = full[1] if hi is None else hi
        fields = self.__dict__
        fields["text"] = text
        fields["typ"] = typ
        fields["deps"] = deps
        fields["lo"] = lo
        fields["hi"] = hi
        fields["prec"] = prec
        fields["var"] = var
        fields["const"] = const
        fields["bool_const"] = bool_const
        fields["parts"] = parts
        fields["names"] = names

    def wrap(self, prec: int) -> str:
        return self.text if self.prec >= prec else f"({self.text})"

    @property
    def simple(self) -> bool:
        return self.var is not None or self.const is not None or self.bool_const is not None or self.prec == PREC_ATOM and "(" not in self.text


def var(name: str, typ: str, deps_name: str | None = None) -> Expr:
    lo, hi = RANGES.get(typ, (0, 0))
    return Expr(name, typ, frozenset([deps_name or base_name(name)]), lo, hi, PREC_ATOM, var=name)


def names_of(e: Expr) -> frozenset[str]:
    """`names_in(e.text)`, from the parts `e` was built of (its variable's reference, its words and operands), or
    read from its text when it has neither; kept with `e` once worked out."""
    found = e.names
    if found is not None:
        return found
    if e.parts is not None:
        found = _NONE
        for p in e.parts:
            if type(p) is str:
                names = _OPERATOR_NAMES.get(p)      # (most words: no call)
                if names is None:
                    names = _word_names(p)
            else:
                names = p.names if p.names is not None else names_of(p)
            if names:       # (a part's own set serves while it is the only one with names: most operands)
                found = found | names if found else names
    elif e.var is not None and e.var == e.text:
        found = text_names(e.text)
    else:
        found = frozenset(names_in(e.text))
    e.__dict__["names"] = found     # (a memo of a fact of the text, which never changes; frozen: set past __setattr__)
    return found


def reference_names(text: str) -> frozenset[str] | None:
    """names_in of a variable reference as the layout writes one: `name`, `member.path` or either behind a list
    qualifier (`GVL_IO.I5`); None for other text (an array element, a deeper path), which is read as text."""
    if _ident(text):
        return frozenset((text.upper(),))
    parts = text.split(".")
    if len(parts) > 1 and parts[0] in GVL_NAMES and _ident(parts[1][:1]):
        parts = parts[1:]       # the list qualifier (as _QUALIFIED takes it: spelled as declared, a name after it)
    if len(parts) == 1 and _ident(parts[0]):
        return frozenset((parts[0].upper(),))
    if len(parts) == 2 and _ident(parts[0]) and _ident(parts[1]):
        return frozenset((parts[0].upper(), f"{parts[0]}.{parts[1]}".upper()))
    return None


def text_names(text: str) -> frozenset[str]:
    """names_in of lvalue or callee text: a plain reference without reading it, other text read."""
    found = reference_names(text)
    return found if found is not None else frozenset(names_in(text))


def _ident(text: str) -> bool:
    """An ASCII identifier, as _PATH reads one."""
    return text.isascii() and text.isidentifier()


def _word_names(word: str) -> frozenset[str]:
    """names_in of a function name or operator joined into an expression's text (`HH_BIT`, `AND`; `+`: none)."""
    known = _OPERATOR_NAMES.get(word)
    if known is not None:
        return known
    if _ident(word):
        return frozenset((word.upper(),))
    return text_names(word) if any(ch.isalnum() or ch == "_" for ch in word) else _NONE


_NONE: frozenset[str] = frozenset()
# The operators binop and b_not join into expressions and the type conversions (most words): their names, worked
# out once.
_OPERATOR_NAMES = MappingProxyType({
    **{op: _NONE for op in ("+", "-", "*", "/", "=", "<>", "<", "<=", ">", ">=")},
    **{op: frozenset((op,)) for op in ("AND", "OR", "XOR", "NOT", "MOD")},
    **{f"{a}_TO_{b}": frozenset((f"{a}_TO_{b}",)) for a in ("BOOL", "SINT", "INT", "DINT", "BYTE")
       for b in ("BOOL", "SINT", "INT", "DINT", "BYTE") if a != b}})


def base_name(text: str) -> str:
    """The variable an lvalue text belongs to (array element `A[3]` -> `A`, `GVL_Words.A[3]` -> `A`)."""
    return unqualified(text).split("[", 1)[0].split(".", 1)[0].upper()


# A global's reference on a qualified_only target: its list's name, a dot, the variable (dialect.py). Otherwise
# only an FB instance is followed by a dot and a name, and none is named like a list: so this is a qualifier.
_QUALIFIED = re.compile(r"(?<![A-Za-z0-9_.])(?:" + "|".join(sorted(map(re.escape, GVL_NAMES), key=len, reverse=True))
                        + r")\.(?=[A-Za-z_])")
# A name or member path (`ML_ax.inpos`) not itself after a dot.
_PATH = re.compile(r"(?<![A-Za-z0-9_.])[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)?")


def unqualified(text: str) -> str:
    """`text` without the list qualifier of a global reference (`GVL_IO.I5` -> `I5`)."""
    if "." not in text:     # (most texts: no qualifier to look for)
        return text
    match = _QUALIFIED.match(text)
    return text[match.end():] if match else text


def names_in(text: str) -> set[str]:
    """The variables expression or lvalue text names (upper case, no list qualifiers): each name, and each member
    path with its head (a marker STRUCT's member `ML_ax.inpos` is a variable of its own)."""
    found: set[str] = set()
    for m in _PATH.finditer(_QUALIFIED.sub("", text)):
        path = m.group(0).upper()
        found |= {path, path.split(".", 1)[0]}
    return found


def target_name(lvalue: str) -> str:
    """The variable an assignment's target text writes (upper case, no list qualifier): a member path stays whole,
    an array element is its array."""
    return unqualified(lvalue).split("[", 1)[0].upper()


def written_name(lvalue: Expr) -> str:
    """The name a store to `lvalue` changes, as the deps of the values that read it name it: the lvalue's own text
    where its deps hold that (a variable, or a member of a marker STRUCT, which is a variable of its own), else the
    variable it belongs to (an array element, an FB instance's output)."""
    own = unqualified(lvalue.text).upper()
    return own if own in lvalue.deps else base_name(lvalue.text)


def int_const(value: int, typ: str = "DINT") -> Expr:
    typed = value < 0 and typ != "DINT"
    text = f"{typ}#{value}" if typed else str(value)
    prec = PREC_ATOM if value >= 0 else PREC_UNARY
    return Expr(text, typ, frozenset(), value, value, prec, const=value, parts=(typ,) if typed else ())


_TRUE, _FALSE = frozenset(("TRUE",)), frozenset(("FALSE",))


def bool_const(value: bool) -> Expr:
    return Expr("TRUE" if value else "FALSE", "BOOL", frozenset(), int(value), int(value), bool_const=value,
                names=_TRUE if value else _FALSE)


def call(fn: str, args: list[Expr], typ: str, lo: int | None = None, hi: int | None = None) -> Expr:
    deps = frozenset().union(*(a.deps for a in args)) if args else frozenset()
    rlo, rhi = RANGES.get(typ, (0, 0))
    return Expr(f"{fn}({', '.join(a.text for a in args)})", typ, deps,
                rlo if lo is None else lo, rhi if hi is None else hi, parts=(fn, *args))


def to_dint(e: Expr) -> Expr:
    """Widen an integer or boolean expression to DINT (the word accumulator's type)."""
    if e.typ == "DINT":
        return e
    if e.const is not None:
        return int_const(e.const)
    if e.typ == "BOOL":
        return Expr(f"BOOL_TO_DINT({e.text})", "DINT", e.deps, 0, 1, parts=("BOOL_TO_DINT", e))
    return Expr(f"{e.typ}_TO_DINT({e.text})", "DINT", e.deps, e.lo, e.hi, parts=(f"{e.typ}_TO_DINT", e))


_COMPARE = MappingProxyType({"=": lambda x, y: x == y, "<>": lambda x, y: x != y, "<": lambda x, y: x < y,
                             "<=": lambda x, y: x <= y, ">": lambda x, y: x > y, ">=": lambda x, y: x >= y})


def binop(op: str, a: Expr, b: Expr, typ: str, prec: int, lo: int | None = None, hi: int | None = None) -> Expr:
    # A comparison of two literals is decided here: `HH_LA := 1 <= 24;` reads as a question the program never asks.
    if op in _COMPARE and a.const is not None and b.const is not None:
        return bool_const(_COMPARE[op](a.const, b.const))
    # Left-associative: the right operand needs parentheses at equal precedence.
    text = f"{a.wrap(prec)} {op} {b.wrap(prec + 1)}"
    rlo, rhi = RANGES.get(typ, (0, 0))
    return Expr(text, typ, a.deps | b.deps, rlo if lo is None else lo, rhi if hi is None else hi, prec,
                parts=(op, a, b))


def b_not(a: Expr) -> Expr:
    if a.bool_const is not None:
        return bool_const(not a.bool_const)
    if a.text.startswith("NOT ") and a.prec == PREC_UNARY:
        inner = a.text[4:]
        if inner.startswith("(") and inner.endswith(")") and _balanced(inner[1:-1]):
            inner = inner[1:-1]
        # (the operand of a NOT built here: the text is its text, parentheses aside)
        parts = a.parts[1:] if a.parts is not None and a.parts[:1] == ("NOT",) else None
        return Expr(inner, "BOOL", a.deps, 0, 1, PREC_OR if inner != a.text[4:] else PREC_ATOM, parts=parts)
    return Expr(f"NOT {a.wrap(PREC_UNARY)}", "BOOL", a.deps, 0, 1, PREC_UNARY, parts=("NOT", a))


def bit_of(word: Expr, k: int, access: bool) -> Expr:
    """Bit k (0..31) of the integer `word`, a variable or the widening of one: `word.k` where the target has bit
    access, else the HH_BIT helper on its DINT value. A SINT or INT repeats its sign bit above its width, so a
    higher bit of it is its top bit."""
    if not access:
        wide = to_dint(word)
        return Expr(f"HH_BIT({wide.text}, {k})", "BOOL", word.deps, 0, 1, parts=("HH_BIT", wide))
    narrow = unwiden(word) or word
    top = {"SINT": 7, "INT": 15}.get(narrow.typ, 31)
    # (a bit number after the dot is no name: `w.3` names what `w` names)
    return Expr(f"{narrow.text}.{min(k, top)}", "BOOL", word.deps, 0, 1, parts=(narrow,))


def unwiden(e: Expr) -> Expr | None:
    """`INT_TO_DINT(W0)` -> `W0` (typed INT): the SINT/INT value inside a widening, or None when `e` is no widening."""
    if e.const is not None:
        return None
    for typ in ("SINT", "INT"):
        prefix = f"{typ}_TO_DINT("
        if e.text.startswith(prefix) and e.text.endswith(")") and _balanced(e.text[len(prefix):-1]):
            inner = e.text[len(prefix):-1]
            atom = unqualified(inner).isidentifier() or inner.endswith(")")
            return Expr(inner, typ, e.deps, e.lo, e.hi, PREC_ATOM if atom else PREC_OR)
    return None


def _balanced(text: str) -> bool:
    depth = 0
    for ch in text:
        depth += ch == "("
        depth -= ch == ")"
        if depth < 0:
            return False
    return depth == 0


def b_and(a: Expr, b: Expr) -> Expr:
    # Expressions only read variables, so a constant side decides or drops out without losing an effect.
    for x, y in ((a, b), (b, a)):
        if x.bool_const is not None:
            return y if x.bool_const else bool_const(False)
    return binop("AND", a, b, "BOOL", PREC_AND, 0, 1)


def b_or(a: Expr, b: Expr) -> Expr:
    for x, y in ((a, b), (b, a)):
        if x.bool_const is not None:
            return bool_const(True) if x.bool_const else y
    return binop("OR", a, b, "BOOL", PREC_OR, 0, 1)


def b_xor(a: Expr, b: Expr) -> Expr:
    return binop("XOR", a, b, "BOOL", PREC_XOR, 0, 1)


def fits(e: Expr, lo: int, hi: int) -> bool:
    return lo <= e.lo and e.hi <= hi
