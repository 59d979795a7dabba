"""Python expression snippets of the generated interpreter code: int32 wrap, sign extension, masks, literals, gates."""

from __future__ import annotations

H, M32 = 2147483648, 4294967295
REL = {"==": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
LOGIC_OPS = ("A", "AN", "O", "ON", "XO", "XON")


def gate(kind: str, left: str, right: str, negate_fmt: str) -> str:
    neg = negate_fmt.format(right)
    return {"A": f"{left} & {right}", "AN": f"{left} & {neg}", "O": f"{left} | {right}",
            "ON": f"{left} | {neg}", "XO": f"{left} ^ {right}", "XON": f"{left} ^ {neg}"}[kind]


def norm(expr: str) -> str:
    """Reduce to int32 (two's complement wrap). A value already in range (nearly always) is taken as it is: the
    range test is cheaper than the wrap arithmetic, whose intermediate values are big ints to allocate. An
    expression other than a name is evaluated once, into `_v`."""
    if expr.isidentifier():
        return f"({expr} if -{H} <= {expr} < {H} else (({expr} + {H}) & {M32}) - {H})"
    return f"(_v if -{H} <= (_v := {expr}) < {H} else ((_v + {H}) & {M32}) - {H})"


def sext_expr(expr: str, bits: int) -> str:
    if bits >= 32:
        return expr
    half = 1 << (bits - 1)
    return f"((({expr}) + {half}) & {(1 << bits) - 1}) - {half}"


def int32(value: int) -> int:
    value &= M32
    return value - (1 << 32) if value > 2147483647 else value


def signed_literal(value: int) -> str:
    return f"({value})" if value < 0 else str(value)


def bit_mask(k: int) -> int:
    """2^k as an int32 (bit 31 is the sign bit)."""
    return -(1 << 31) if k == 31 else 1 << k
