"""ctypes bindings of the C runtime shim: builds/loads libhhshim.so and wraps the NC model and the PLC module table."""

from __future__ import annotations

import ctypes
import dataclasses
import fcntl
import functools
import hashlib
import os
import shlex
import shutil
import subprocess
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence, TypeVar

from transpiler import __version__
from transpiler.resources import DataMissing, cache_dir, data_dir

LIB_NAME = "libhhshim.so"

# Mirrors of the C constants (hh_nc.h, hh_modules.h).
NC_MAX_WRITES = 32
MODULE_MAX_PARAMS = 8
MODULE_MAX_RESULTS = 8
EXTRA_TIMER_COUNT = 904
NC_STATES = ("IDLE", "WAIT_ACK", "WAIT_ACK_RESET")
MODULE_KINDS = ("unknown", "stub", "modelled")
PROFILE_NUMBERS = {"itnc530": 0, "tnc426": 0, "tv": 0, "tnc407": 1}
_PROFILE_NAMES = {0: "itnc530/tnc426/tv", 1: "tnc407"}
_INT32 = (-(2**31), 2**31 - 1)

Write = tuple[str, int, int]
"""One operand write: (kind 'M'/'W'/'D'/'T', address, value); W values are already sign-extended from 16 bits."""


class ShimUnavailable(RuntimeError):
    """The runtime shim library could not be built or loaded (the message says what is missing, or carries the
    compiler's output)."""


class NcActionError(ValueError):
    """A scenario nc action that is malformed, out of range, or not supported by the profile."""


class UnknownModule(ValueError):
    """A PLC module number without any entry in the shared module table (E-RT-MODULE when executed)."""


class HandshakeTimeout(Exception):
    """E-SIM-HANDSHAKE-TIMEOUT: an NC handshake did not complete within 10 s of simulated time."""

    code = "E-SIM-HANDSHAKE-TIMEOUT"

    def __init__(self, cycle: int, function: str, started: int = -1, strobe: int = 0, ack: int = 0):
        self.cycle = cycle
        self.function = function
        self.started = started
        self.strobe = strobe
        self.ack = ack
        super().__init__(
            f"the PLC did not complete the {function} handshake (strobe M{strobe}, acknowledgement M{ack}) "
            f"started in cycle {started} within 10 s; reported in cycle {cycle}")


class _Write(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_char), ("addr", ctypes.c_int32), ("value", ctypes.c_int32)]


_READ_BIT = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_void_p, ctypes.c_int32)


# ---------------------------------------------------------------------------------------------
# building and loading


# The flags of runtime_shim/Makefile (which builds the C unit tests); -fwrapv: signed overflow wraps, as on the control.
SHIM_CFLAGS = ("-std=c99", "-Wall", "-Wextra", "-pedantic", "-O2", "-fwrapv", "-fPIC", "-shared")
COMPILERS = ("cc", "gcc")
"""Looked for on PATH, in this order, when $CC is not set."""


def shim_sources() -> Path:
    """The folder of the shim's C sources: installed with the package, else the checkout's runtime_shim/."""
    try:
        return data_dir("runtime_shim")
    except DataMissing as exc:
        raise ShimUnavailable(f"cannot build the runtime shim: {exc}") from None


def _sources(root: Path) -> list[Path]:
    return sorted(p for pattern in ("*.c", "*.h") for p in root.glob(pattern))


def cache_key(root: Path) -> str:
    """<version>-<hash of the sources and flags>: a changed source or flag builds a new library beside the old one,
    so two hh2iec versions (or checkouts) sharing one cache never load each other's library."""
    digest = hashlib.sha256(" ".join(SHIM_CFLAGS).encode())
    for path in _sources(root):
        digest.update(b"\0" + path.name.encode() + b"\0" + path.read_bytes())
    return f"{__version__}-{digest.hexdigest()[:16]}"


def _is_stale(root: Path, lib: Path) -> bool:
    if not lib.exists():
        return True
    sources = _sources(root)
    if not sources:  # a shipped library without its sources: use it as it is
        return False
    return lib.stat().st_mtime_ns < max(p.stat().st_mtime_ns for p in sources)


def find_compiler() -> list[str]:
    """The C compiler command: $CC when set, else cc or gcc from PATH; ShimUnavailable naming what was looked for."""
    configured = os.environ.get("CC", "").strip()
    if configured:
        argv = shlex.split(configured)
        if shutil.which(argv[0]):
            return argv
        raise ShimUnavailable(f"cannot build the runtime shim: the C compiler named by CC ({configured!r}) was not "
                              "found; install it or point CC at a C compiler")
    for name in COMPILERS:
        found = shutil.which(name)
        if found:
            return [found]
    raise ShimUnavailable("cannot build the runtime shim: no C compiler found (looked for "
                          f"{' and '.join(repr(c) for c in COMPILERS)} on PATH, and CC is not set); install one "
                          "(e.g. 'apt-get install gcc') or set CC")


def _compile(root: Path, lib: Path) -> None:
    command = [*find_compiler(), *SHIM_CFLAGS]
    # Written under a temporary name and renamed: a process loading the library never sees a half-written file.
    tmp = lib.with_name(f"{lib.name}.tmp.{os.getpid()}")
    argv = [*command, "-o", str(tmp), *(str(p) for p in sorted(root.glob("*.c")))]
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        raise ShimUnavailable(f"building the runtime shim timed out ({' '.join(argv)})") from None
    except OSError as exc:
        raise ShimUnavailable(f"cannot run the C compiler {argv[0]}: {exc}") from None
    if proc.returncode != 0:
        tmp.unlink(missing_ok=True)
        output = (proc.stderr.strip() or proc.stdout.strip() or f"exit status {proc.returncode}")
        raise ShimUnavailable(f"building the runtime shim failed ({' '.join(argv)}):\n{output}")
    os.replace(tmp, lib)


def ensure_built(root: Path | str | None = None) -> Path:
    """Path of the shim library, compiled first when it is missing or older than its sources.

    By default the sources are the installed (or checkout) runtime_shim/ and the library goes to the per-user cache,
    <cache>/shim-<version>-<hash>/ (see transpiler.resources.cache_dir): never into the package, which may be
    read-only. An explicit `root` (a folder of shim sources) builds into root/build/."""
    if root is not None:
        root = Path(root)
        out = root / "build"
    else:
        root = shim_sources()
        out = cache_dir() / f"shim-{cache_key(root)}"
    lib = out / LIB_NAME
    if not _is_stale(root, lib):
        return lib
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = open(out / ".lock", "w")
    except OSError as exc:
        raise ShimUnavailable(f"cannot build the runtime shim in {out}: {exc} (set HH2IEC_CACHE to a writable "
                              "folder)") from None
    with lock:
        # Other processes (parallel test runs, the CLI) may build at the same time.
        fcntl.flock(lock, fcntl.LOCK_EX)
        if _is_stale(root, lib):
            _compile(root, lib)
    if not lib.exists():
        raise ShimUnavailable(f"building the runtime shim did not produce {lib}")
    return lib


def load_shim(root: Path | str | None = None) -> ctypes.CDLL:
    """The loaded shim library (built first if needed); raises ShimUnavailable, never a raw OSError."""
    return _open_library(str(ensure_built(root)))


# The dynamic loader keeps one handle per path for the life of the process anyway; caching it
# here also declares the ctypes prototypes once instead of on every NcModel/SysModules.
@functools.lru_cache(maxsize=None)
def _open_library(path: str) -> ctypes.CDLL:
    try:
        lib = ctypes.CDLL(path)
        _declare(lib)
    except (OSError, AttributeError) as exc:
        raise ShimUnavailable(f"cannot load the runtime shim {path}: {exc}") from None
    return lib


def _declare(lib: ctypes.CDLL) -> None:
    i32, i64, p, cp = ctypes.c_int32, ctypes.c_int64, ctypes.c_void_p, ctypes.c_char_p
    pi32, pi64 = ctypes.POINTER(i32), ctypes.POINTER(i64)
    c_int = ctypes.c_int
    prototypes: dict[str, tuple[Any, list[Any]]] = {
        "hh_nc_new": (p, [i32, i32]),
        "hh_nc_free": (None, [p]),
        "hh_nc_set_first_cycle_marker": (c_int, [p, i32]),
        "hh_nc_m_function": (c_int, [p, i32]),
        "hh_nc_spindle_speed": (c_int, [p, i32]),
        "hh_nc_gear": (c_int, [p, i32]),
        "hh_nc_tool_call": (c_int, [p, i32, i32, i32]),
        "hh_nc_tool_def": (c_int, [p, i32, i32]),
        "hh_nc_fn19": (c_int, [p, i32, i32]),
        "hh_nc_mode": (c_int, [p, i32]),
        "hh_nc_restart": (c_int, [p, i32]),
        "hh_nc_phase": (c_int, [p, i64, _READ_BIT, p, ctypes.POINTER(_Write), c_int]),
        "hh_nc_pending": (i32, [p]),
        "hh_nc_state": (i32, [p]),
        "hh_nc_active_function": (cp, [p]),
        "hh_nc_error": (cp, [p, pi64]),
        "hh_nc_error_detail": (c_int, [p, pi64, pi32, pi32]),
        "hh_module_info": (c_int, [i32, pi32, pi32]),
        "hh_module_purpose": (cp, [i32]),
        "hh_module_count": (i32, []),
        "hh_module_number_at": (i32, [i32]),
        "hh_module_call": (c_int, [p, i32, pi32, pi32, pi32]),
        "hh_sys_new": (p, [i32]),
        "hh_sys_free": (None, [p]),
        "hh_sys_set_mp": (c_int, [p, i32, i32, i64, i32]),
        "hh_sys_get_mp": (c_int, [p, i32, i32, pi64, pi32]),
        "hh_sys_set_number_mp4111": (c_int, [p, i32]),
        "hh_sys_set_timer_unit": (None, [p, i32]),
        "hh_sys_set_timer_restart": (None, [p, i32]),
        "hh_sys_set_status": (c_int, [p, i32, i32]),
        "hh_sys_set_module_result": (c_int, [p, i32, i32, i32]),
        "hh_sys_clear_module_results": (None, [p, i32]),
        "hh_sys_tick": (None, [p]),
        "hh_sys_cycle": (i64, [p]),
        "hh_sys_time_ms": (i64, [p]),
        "hh_sys_service": (c_int, [p, ctypes.POINTER(_Write), c_int]),
        "hh_sys_timer_running": (c_int, [p, i32]),
    }
    for name, (restype, argtypes) in prototypes.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


def _int32(value: Any, what: str, error: type[Exception] = ValueError) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise error(f"{what} must be an integer, not {value!r}")
    if not _INT32[0] <= value <= _INT32[1]:
        raise error(f"{what} {value} is outside the 32-bit range")
    return value


def _writes(buf: ctypes.Array, n: int) -> list[Write]:
    return [(w.kind.decode("ascii"), w.addr, w.value) for w in buf[:n]]


def _check_cycle_time(cycle_time_ms: Any) -> None:
    _int32(cycle_time_ms, "cycle_time_ms")
    if cycle_time_ms <= 0:
        raise ValueError(f"cycle_time_ms must be positive, not {cycle_time_ms}")


_O = TypeVar("_O", bound="_Owned")


class _Owned:
    """Owner of one C object of the shim, freed by close(), by a with block or when garbage-collected."""

    _handle: Any = None
    _lib: ctypes.CDLL
    _FREE: str                      # name of the C function that frees the object

    def close(self) -> None:
        if self._handle:
            getattr(self._lib, self._FREE)(self._handle)
            self._handle = None

    def __del__(self) -> None:
        self.close()

    def __enter__(self: _O) -> _O:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ---------------------------------------------------------------------------------------------
# NC model


class _ReadSlot:
    """Holds the Python read_bit callable for the one C callback of an NcModel.

    ctypes swallows exceptions raised inside callbacks, so they are kept here and re-raised
    after the C call returns.
    """

    __slots__ = ("reader", "error")

    def __init__(self) -> None:
        self.reader: Callable[[int], int] | None = None
        self.error: BaseException | None = None

    def __call__(self, _ctx: Any, marker: int) -> int:
        try:
            return 1 if self.reader(marker) else 0  # type: ignore[misc]
        except BaseException as exc:  # noqa: BLE001 - re-raised by NcModel.phase
            self.error = exc
            return 0


def _profile_number(profile: int | str) -> int:
    if isinstance(profile, str):
        if profile not in PROFILE_NUMBERS:
            raise ValueError(f"unknown profile {profile!r} (known: {', '.join(PROFILE_NUMBERS)})")
        return PROFILE_NUMBERS[profile]
    if profile not in _PROFILE_NAMES:
        raise ValueError(f"unknown NC profile number {profile!r} (0 itnc530/tnc426/tv, 1 tnc407)")
    return profile


def _fields(value: Any, action: str, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise NcActionError(f"nc action {action!r} expects a mapping with {', '.join(required)}, not {value!r}")
    unknown = sorted(set(value) - set(required) - set(optional))
    if unknown:
        raise NcActionError(f"nc action {action!r}: unknown key(s) {', '.join(map(str, unknown))}")
    missing = [k for k in required if k not in value]
    if missing:
        raise NcActionError(f"nc action {action!r}: missing key(s) {', '.join(missing)}")
    return dict(value)


def _nc_args(action: str, value: Any) -> tuple[int, ...]:
    """C arguments of a scenario nc action (see docs/scenarios.md#nc-actions), validated."""
    def num(v: Any, what: str) -> int:
        return _int32(v, f"nc action {action!r}: {what}", NcActionError)

    if action in ("m_function", "spindle_speed", "gear", "mode"):
        return (num(value, "value"),)
    if action == "tool_call":
        f = _fields(value, action, ("tool", "pocket"), ("second_strobe",))
        second = f.get("second_strobe", False)
        if not isinstance(second, bool):
            raise NcActionError(f"nc action 'tool_call': second_strobe must be true or false, not {second!r}")
        return (num(f["tool"], "tool"), num(f["pocket"], "pocket"), int(second))
    if action == "tool_def":
        f = _fields(value, action, ("tool", "pocket"))
        return (num(f["tool"], "tool"), num(f["pocket"], "pocket"))
    if action == "fn19":
        f = _fields(value, action, ("value1", "value2"))
        return (num(f["value1"], "value1"), num(f["value2"], "value2"))
    if action == "restart":
        kinds = {"program": 0, "machine_parameters": 1}
        if value not in kinds:
            raise NcActionError(f"nc action 'restart' expects program or machine_parameters, not {value!r}")
        return (kinds[value],)
    raise NcActionError(f"unknown nc action {action!r} (known: m_function, spindle_speed, gear, tool_call, "
                        "tool_def, fn19, mode, restart)")


class NcModel(_Owned):
    """The NC side of the strobe/acknowledge interface, played from scenario nc actions.

    `first_cycle_marker` (A-38) is the marker pulsed in cycles 0 and 1 instead of M4172 (ITNC profile).
    """

    _FREE = "hh_nc_free"

    def __init__(self, cycle_time_ms: int = 20, profile: int | str = 0, *, first_cycle_marker: int | None = None,
                 lib: ctypes.CDLL | None = None):
        self._lib = lib if lib is not None else load_shim()
        self._profile = _profile_number(profile)
        _check_cycle_time(cycle_time_ms)
        self._handle = self._lib.hh_nc_new(cycle_time_ms, self._profile)
        if not self._handle:
            raise MemoryError("hh_nc_new failed")
        if first_cycle_marker is not None and self._lib.hh_nc_set_first_cycle_marker(
                self._handle, _int32(first_cycle_marker, "first_cycle_marker")) != 0:
            raise ValueError(f"first_cycle_marker must not be negative, not {first_cycle_marker}")
        self._out = (_Write * NC_MAX_WRITES)()
        self._slot = _ReadSlot()
        self._callback = _READ_BIT(self._slot)
        self._phase_fn = self._lib.hh_nc_phase
        self._next_cycle = 0
        self._enqueue_fns = {
            "m_function": self._lib.hh_nc_m_function, "spindle_speed": self._lib.hh_nc_spindle_speed,
            "gear": self._lib.hh_nc_gear, "tool_call": self._lib.hh_nc_tool_call,
            "tool_def": self._lib.hh_nc_tool_def, "fn19": self._lib.hh_nc_fn19,
            "mode": self._lib.hh_nc_mode, "restart": self._lib.hh_nc_restart,
        }

    def enqueue(self, action: Mapping[str, Any]) -> None:
        """Queue one scenario nc action, e.g. {'m_function': 3} or {'tool_call': {'tool': 5, 'pocket': 2}}."""
        if not isinstance(action, Mapping) or len(action) != 1:
            raise NcActionError(f"an nc action is a mapping with exactly one key, not {action!r}")
        ((name, value),) = action.items()
        args = _nc_args(name, value)
        rc = self._enqueue_fns[name](self._handle, *args)
        if rc == -1:
            raise NcActionError(f"nc action {name!r} is not supported by profile {_PROFILE_NAMES[self._profile]}")
        if rc == -2:
            raise NcActionError(f"nc action {name!r}: value {value!r} does not fit its 16-bit code word")
        if rc != 0:
            raise MemoryError(f"hh_nc enqueue failed ({rc})")

    def phase(self, cycle: int, read_bit: Callable[[int], int]) -> list[Write]:
        """Phase 1 of `cycle` (0, 1, 2, ...): the writes to apply, in order; raises HandshakeTimeout."""
        slot = self._slot
        slot.reader = read_bit
        slot.error = None
        n = self._phase_fn(self._handle, cycle, self._callback, None, self._out, NC_MAX_WRITES)
        slot.reader = None
        if slot.error is not None:
            raise slot.error
        if n >= 0:
            self._next_cycle = cycle + 1
            return _writes(self._out, n) if n else []
        if n == -1:
            raise self.error  # type: ignore[misc]
        if n == -3:
            raise ValueError(f"NC phase for cycle {cycle}: cycles must run 0, 1, 2, ... (expected {self._next_cycle})")
        raise RuntimeError(f"hh_nc_phase failed ({n})")

    @property
    def pending(self) -> int:
        """Actions queued and not yet completed (including the one in progress)."""
        return self._lib.hh_nc_pending(self._handle)

    @property
    def state(self) -> str:
        return NC_STATES[self._lib.hh_nc_state(self._handle)]

    @property
    def active_function(self) -> str | None:
        name = self._lib.hh_nc_active_function(self._handle)
        return name.decode() if name is not None else None

    @property
    def error(self) -> HandshakeTimeout | None:
        cycle, started = ctypes.c_int64(), ctypes.c_int64()
        strobe, ack = ctypes.c_int32(), ctypes.c_int32()
        name = self._lib.hh_nc_error(self._handle, ctypes.byref(cycle))
        if name is None:
            return None
        self._lib.hh_nc_error_detail(self._handle, ctypes.byref(started), ctypes.byref(strobe), ctypes.byref(ack))
        return HandshakeTimeout(cycle.value, name.decode(), started.value, strobe.value, ack.value)


# ---------------------------------------------------------------------------------------------
# PLC modules and the simulated system context


@dataclasses.dataclass(frozen=True)
class ModuleInfo:
    """One entry of the shared module table: kind is 'unknown', 'stub' or 'modelled'."""

    number: int
    kind: str
    nparams: int
    nresults: int
    purpose: str

    @property
    def known(self) -> bool:
        return self.kind != "unknown"


def module_info(number: int, *, lib: ctypes.CDLL | None = None) -> ModuleInfo:
    """Table entry of module `number` (no system context needed, e.g. for compile-time checks)."""
    lib = lib if lib is not None else load_shim()
    _int32(number, "module number")
    np, nr = ctypes.c_int32(), ctypes.c_int32()
    kind = lib.hh_module_info(number, ctypes.byref(np), ctypes.byref(nr))
    return ModuleInfo(number, MODULE_KINDS[kind], np.value, nr.value, lib.hh_module_purpose(number).decode())


def module_table(*, lib: ctypes.CDLL | None = None) -> list[ModuleInfo]:
    """Every module number the shared table knows, in table order."""
    lib = lib if lib is not None else load_shim()
    return [module_info(lib.hh_module_number_at(i), lib=lib) for i in range(lib.hh_module_count())]


def _fixed_point(value: Any) -> tuple[int, int]:
    """(mantissa, decimals) of an MP value, keeping its written decimals: '0.50' -> (50, 2)."""
    if isinstance(value, bool):
        raise ValueError(f"machine parameter value must be a number, not {value!r}")
    try:
        if isinstance(value, float):
            dec = Decimal(repr(value))  # the shortest text that round-trips: 0.1 -> Decimal('0.1')
        elif isinstance(value, (int, Decimal)):
            dec = Decimal(value)
        elif isinstance(value, str):
            dec = Decimal(value.strip())
        else:
            raise ValueError(f"machine parameter value must be a number, not {value!r}")
    except InvalidOperation:
        raise ValueError(f"machine parameter value {value!r} is not a number") from None
    if not dec.is_finite():
        raise ValueError(f"machine parameter value {value!r} is not finite")
    if dec.as_tuple().exponent < -9:  # type: ignore[operator]
        dec = dec.normalize()  # '0.5000000000' still fits: drop the trailing zeros
    sign, digits, exponent = dec.as_tuple()
    mantissa = int("".join(map(str, digits)) or "0") * (-1 if sign else 1)
    if exponent > 0:  # type: ignore[operator]
        return mantissa * 10**exponent, 0  # type: ignore[operator]
    return mantissa, -exponent  # type: ignore[operator]


class SysModules(_Owned):
    """The simulated system context of the PLC modules: clock, MPs, status table, T96-T999 (module 9006)."""

    _FREE = "hh_sys_free"

    def __init__(self, cycle_time_ms: int = 20, *, number_mp4111: int = 0, timer_unit: str = "seconds",
                 timer_restart: bool = True, lib: ctypes.CDLL | None = None):
        self._lib = lib if lib is not None else load_shim()
        _check_cycle_time(cycle_time_ms)
        if timer_unit not in ("seconds", "cycles"):
            raise ValueError(f"timer_unit must be seconds or cycles, not {timer_unit!r}")
        self._handle = self._lib.hh_sys_new(cycle_time_ms)
        if not self._handle:
            raise MemoryError("hh_sys_new failed")
        self._params = (ctypes.c_int32 * MODULE_MAX_PARAMS)()
        self._results = (ctypes.c_int32 * MODULE_MAX_RESULTS)()
        self._code = ctypes.c_int32()
        self._timer_out = (_Write * EXTRA_TIMER_COUNT)()
        self._info: dict[int, ModuleInfo] = {}
        self._call_fn = self._lib.hh_module_call
        self._service_fn = self._lib.hh_sys_service
        self._tick_fn = self._lib.hh_sys_tick
        self._lib.hh_sys_set_timer_unit(self._handle, timer_unit == "cycles")
        self._lib.hh_sys_set_timer_restart(self._handle, bool(timer_restart))
        self.set_number_mp4111(number_mp4111)

    def info(self, number: int) -> ModuleInfo:
        entry = self._info.get(number)
        if entry is None:
            entry = self._info[number] = module_info(number, lib=self._lib)
        return entry

    def call(self, number: int, params: Sequence[int]) -> tuple[list[int], int, int | None]:
        """Run module `number` with params in push order: (results with result 1 first, M4203 value,
        W1022 value or None when the call did not fail). Raises UnknownModule for a number without entry."""
        entry = self.info(number)
        if not entry.known:
            raise UnknownModule(f"PLC module {number} has no entry in the module table")
        if len(params) != entry.nparams:
            raise ValueError(f"module {number} takes {entry.nparams} parameter(s), got {len(params)}")
        buf = self._params
        for i, value in enumerate(params):
            buf[i] = value
        status = self._call_fn(self._handle, number, buf, self._results, ctypes.byref(self._code))
        return list(self._results[:entry.nresults]), status, (self._code.value if status else None)

    def service(self) -> list[Write]:
        """Phase 3 service of T96-T999: the running value of every configured additional timer, as 'T' writes."""
        n = self._service_fn(self._handle, self._timer_out, EXTRA_TIMER_COUNT)
        return _writes(self._timer_out, n) if n > 0 else []

    def tick(self) -> None:
        """Advance the simulated clock by one cycle (scenario step 5)."""
        self._tick_fn(self._handle)

    @property
    def cycle(self) -> int:
        return self._lib.hh_sys_cycle(self._handle)

    @property
    def time_ms(self) -> int:
        return self._lib.hh_sys_time_ms(self._handle)

    def timer_running(self, n: int) -> int:
        return self._lib.hh_sys_timer_running(self._handle, _int32(n, "timer number"))

    def set_mp(self, number: int, index: int, value: int | float | str | Decimal) -> None:
        """Machine parameter number.index; decimals are kept as written ('0.125' s, 10 cycles)."""
        mantissa, decimals = _fixed_point(value)
        if self._lib.hh_sys_set_mp(self._handle, _int32(number, "MP number"), _int32(index, "MP index"),
                                   mantissa, decimals) != 0:
            raise ValueError(f"machine parameter {number}.{index} = {value!r}: more than 9 decimals or 15 digits")

    def get_mp(self, number: int, index: int) -> Decimal | None:
        """Run-time value of an MP (after module 9031), None when it was never set."""
        mantissa, decimals = ctypes.c_int64(), ctypes.c_int32()
        if not self._lib.hh_sys_get_mp(self._handle, _int32(number, "MP number"), _int32(index, "MP index"),
                                       ctypes.byref(mantissa), ctypes.byref(decimals)):
            return None
        return Decimal(mantissa.value).scaleb(-decimals.value)

    def set_number_mp4111(self, count: int) -> None:
        """NUMBERMP4111 of OEM.SYS: how many additional timers (T96 ...) module 9006 may start."""
        if self._lib.hh_sys_set_number_mp4111(self._handle, _int32(count, "NUMBERMP4111")) != 0:
            raise ValueError(f"NUMBERMP4111 must be 0 ... {EXTRA_TIMER_COUNT}, not {count}")

    def set_status(self, number: int, value: int) -> None:
        """Entry of the status table that modules 9035/9036 read and write."""
        if self._lib.hh_sys_set_status(self._handle, _int32(number, "status number"), _int32(value, "value")) != 0:
            raise ValueError(f"status number {number} is outside the status table")

    def set_module_result(self, number: int, index: int, value: int) -> None:
        """Scenario override of result `index` (0 = result 1) of module `number`."""
        if self._lib.hh_sys_set_module_result(self._handle, _int32(number, "module number"),
                                              _int32(index, "result index"), _int32(value, "value")) != 0:
            info = self.info(number)
            if not info.known:
                raise UnknownModule(f"PLC module {number} has no entry in the module table")
            raise ValueError(f"module {number} has {info.nresults} result(s); cannot override result {index + 1}")

    def set_module_results(self, number: int, values: Sequence[int]) -> None:
        """Scenario `module_results: {number: [v1, v2, ...]}`: replaces earlier overrides of the module."""
        self.clear_module_results(number)
        for index, value in enumerate(values):
            self.set_module_result(number, index, value)

    def clear_module_results(self, number: int) -> None:
        self._lib.hh_sys_clear_module_results(self._handle, _int32(number, "module number"))
