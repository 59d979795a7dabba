"""Run-time helpers that the Python code compiled from ST calls: exact arithmetic, conversions, string functions."""

from __future__ import annotations

import math
import re
import struct
from types import MappingProxyType

from transpiler.exec.stexec.errors import Trap
from transpiler.exec.stexec.typesys import STR_MAX

_F32 = struct.Struct("<f")
_INF = math.inf


# ------------------------------------------------------------------ numbers

def wrap_int(value: int, bits: int, signed: bool) -> int:
    """The low `bits` bits of value, read as two's complement when signed: how every integer type wraps around."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if signed and value >> (bits - 1) else value


def f32(x: float) -> float:
    """Round a Python float to IEEE single precision, as a REAL variable would hold it."""
    try:
        return _F32.unpack(_F32.pack(x))[0]
    except OverflowError:
        return math.copysign(_INF, x)


def idiv(a: int, b: int) -> int:
    """Integer `/`: truncation toward zero (C semantics, as matiec generates)."""
    if b == 0:
        raise Trap("division by zero")
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def imod(a: int, b: int) -> int:
    """Integer MOD: the remainder has the sign of the dividend (C `%`)."""
    if b == 0:
        raise Trap("MOD by zero")
    r = abs(a) % abs(b)
    return r if a >= 0 else -r


def div_fn(a, b):
    """The standard function DIV: matiec returns 0 (and ENO FALSE) for a zero divisor instead of trapping."""
    if b == 0:
        return 0.0 if isinstance(a, float) else 0
    if isinstance(a, float) or isinstance(b, float):
        return a / b
    return idiv(a, b)


def mod_fn(a: int, b: int) -> int:
    return 0 if b == 0 else imod(a, b)


def fdiv(a: float, b: float) -> float:
    """REAL division with IEEE results for a zero divisor (inf, -inf or nan) instead of a Python exception."""
    try:
        return a / b
    except ZeroDivisionError:
        if a == 0 or a != a:
            return math.nan
        return math.copysign(_INF, a) * math.copysign(1.0, b)


def fpow(a: float, b: float) -> float:
    try:
        return math.pow(a, b)
    except OverflowError:
        return _INF
    except ValueError:
        return math.nan


def fmath(fn, x: float) -> float:
    try:
        return fn(x)
    except (ValueError, OverflowError):
        return math.nan


def real_to_int(x: float, bits: int, signed: bool) -> int:
    """REAL_TO_<int>: round half to even (measured on matiec), then keep the low bits."""
    if x != x or x in (_INF, -_INF):
        raise Trap(f"REAL value {x} cannot be converted to an integer")
    return wrap_int(round(x), bits, signed)


def trunc(x: float) -> int:
    if x != x or x in (_INF, -_INF):
        raise Trap(f"TRUNC of {x}")
    return int(x)


def limit(mn, x, mx):
    """LIMIT(MN, IN, MX) = MIN(MAX(IN, MN), MX) as IEC 61131-3 defines it."""
    v = mn if x < mn else x
    return mx if v > mx else v


def mux(k: int, *values):
    if 0 <= k < len(values):
        return values[k]
    raise Trap(f"MUX selector K={k} outside 0..{len(values) - 1}")


def rol(x: int, n: int, bits: int) -> int:
    if n < 0:
        raise Trap(f"negative rotate count {n}")
    n %= bits
    return ((x << n) | (x >> (bits - n))) & ((1 << bits) - 1)


def ror(x: int, n: int, bits: int) -> int:
    if n < 0:
        raise Trap(f"negative rotate count {n}")
    n %= bits
    return ((x >> n) | (x << (bits - n))) & ((1 << bits) - 1)


def bcd_to_int(x: int) -> int:
    value, scale = 0, 1
    while x:
        value += (x & 0xF) * scale
        x >>= 4
        scale *= 10
    return value


def int_to_bcd(v: int, bits: int) -> int:
    out, shift = 0, 0
    v = abs(v)
    while v and shift < bits:
        out |= (v % 10) << shift
        v //= 10
        shift += 4
    return out & ((1 << bits) - 1)


def oob(indices, dims) -> None:
    raise Trap(f"array index {list(indices)} outside {', '.join(f'{lo}..{hi}' for lo, hi in dims)}")


def loop_trap(limit_: int) -> None:
    raise Trap(f"loop watchdog: more than {limit_} iterations in one loop")


# ------------------------------------------------------------------ TIME (int milliseconds)

def time_to_secs(ms: int) -> int:
    """TIME_TO_<int> counts whole seconds on matiec (targets.md 1.3), truncated toward zero."""
    return idiv(ms, 1000)


def real_to_time(x: float) -> int:
    if x != x or x in (_INF, -_INF):
        raise Trap(f"REAL value {x} cannot be converted to TIME")
    return round(x * 1000)


def time_mul(t: int, k) -> int:
    return int(t * k) if isinstance(k, float) else t * k


def time_div(t: int, k) -> int:
    if k == 0:
        raise Trap("division by zero")
    if isinstance(k, float):
        return int(t / k)
    return idiv(t, k)


# ------------------------------------------------------------------ strings

def _clip(s: str) -> str:
    return s[:STR_MAX]


def concat(*parts: str) -> str:
    return "".join(parts)[:STR_MAX]


def s_left(s: str, n: int) -> str:
    return s[:n] if n > 0 else ""


def s_right(s: str, n: int) -> str:
    return s[len(s) - n:] if n > 0 else ""


def s_mid(s: str, n: int, p: int) -> str:
    if n <= 0 or p < 1 or p > len(s):
        return ""
    return s[p - 1:p - 1 + n]


def s_insert(s1: str, s2: str, p: int) -> str:
    if p < 0:
        return ""
    return _clip(s1[:p] + s2 + s1[p:])


def s_delete(s: str, n: int, p: int) -> str:
    if n < 0 or p < 1 or p > len(s):
        return s
    return s[:p - 1] + s[p - 1 + n:]


def s_replace(s1: str, s2: str, n: int, p: int) -> str:
    if n < 0 or p < 1:
        return s1
    p = min(p, len(s1) + 1)
    return _clip(s1[:p - 1] + s2 + s1[p - 1 + n:])


def s_find(s1: str, s2: str) -> int:
    if not s2:
        return 0
    return s1.find(s2) + 1


def bool_to_string(b: bool) -> str:
    return "TRUE" if b else "FALSE"


def bits_to_string(x: int) -> str:
    return "16#%x" % x


def real_to_string(x: float) -> str:
    return ("%.10g" % x)[:STR_MAX]


def time_to_string(ms: int) -> str:
    """Same layout as matiec's __time_to_string: T#<d>d<h>h<m>m<s>s<ms>ms, trailing zero parts dropped."""
    sign = "-" if ms < 0 else ""
    ms = abs(ms)
    secs, frac = divmod(ms, 1000)
    days, rem = divmod(secs, 86400)
    hours, rem2 = divmod(rem, 3600)
    minutes, seconds = divmod(rem2, 60)
    if frac == 0 and rem == 0:
        return f"T#{sign}{days}d"
    if frac == 0 and rem2 == 0:
        return f"T#{sign}{days}d{hours}h"
    if frac == 0 and seconds == 0:
        return f"T#{sign}{days}d{hours}h{minutes}m"
    if frac == 0:
        return f"T#{sign}{days}d{hours}h{minutes}m{seconds}s"
    return f"T#{sign}{days}d{hours}h{minutes}m{seconds}s{'%g' % frac}ms"


def string_to_int(s: str) -> int:
    """matiec's string-to-integer scan: 2#/8#/16# prefixes (other characters skipped), otherwise the decimal
    digits after the last letter or dot, with a leading '-' giving the sign."""
    for prefix, base_, digits in (("2#", 2, "01"), ("8#", 8, "01234567"), ("16#", 16, "0123456789abcdefABCDEF")):
        if s.startswith(prefix):
            value = 0
            for ch in s[len(prefix):]:
                if ch in digits:
                    value = value * base_ + int(ch, 16)
            return value & 0xFFFFFFFFFFFFFFFF
    if not s:
        return 0
    sign = -1 if s[0] == "-" else 1
    value, scale, count = 0, 1, 0
    for ch in reversed(s):
        if count >= 20:
            break
        if "0" <= ch <= "9":
            value += (ord(ch) - 48) * scale
            scale *= 10
            count += 1
        elif ch >= ".":
            value, scale, count = 0, 1, 0
    return sign * value


_FLOAT_PREFIX = re.compile(r"\s*[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


def string_to_real(s: str) -> float:
    if "." in s:
        m = _FLOAT_PREFIX.match(s)
        return float(m.group(0)) if m else 0.0
    return float(string_to_int(s))


def string_to_bool(s: str) -> bool:
    if len(s) == 1:
        return s == "1"
    return s.upper() == "TRUE"


def string_to_time(s: str) -> int:
    if "." in s:
        return round(string_to_real(s) * 1000)
    return string_to_int(s) * 1000


def sinit(obj, **fields):
    """An FB instance or struct with some members set: what an initialiser `(PT := T#1s)` builds."""
    for k, v in fields.items():
        setattr(obj, k, v)
    return obj


def aset(dst: list, src: list) -> None:
    """Array assignment for arrays of structs: copy element by element into the existing objects."""
    for d, s in zip(dst, src):
        d._set(s)


HELPERS = MappingProxyType({
    "_f32": f32, "_idiv": idiv, "_imod": imod, "_div_fn": div_fn, "_mod_fn": mod_fn, "_fdiv": fdiv,
    "_fpow": fpow, "_fmath": fmath, "_real_to_int": real_to_int, "_trunc": trunc, "_limit": limit, "_mux": mux,
    "_rol": rol, "_ror": ror, "_bcd_to_int": bcd_to_int, "_int_to_bcd": int_to_bcd, "_oob": oob,
    "_loop_trap": loop_trap, "_time_to_secs": time_to_secs, "_real_to_time": real_to_time, "_time_mul": time_mul,
    "_time_div": time_div, "_concat": concat, "_s_left": s_left, "_s_right": s_right, "_s_mid": s_mid,
    "_s_insert": s_insert, "_s_delete": s_delete, "_s_replace": s_replace, "_s_find": s_find,
    "_bool_to_string": bool_to_string, "_bits_to_string": bits_to_string, "_real_to_string": real_to_string,
    "_time_to_string": time_to_string, "_string_to_int": string_to_int, "_string_to_real": string_to_real,
    "_string_to_bool": string_to_bool, "_string_to_time": string_to_time, "_sinit": sinit,
    "_aset": aset, "_math": math,
})
