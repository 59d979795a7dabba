"""The matiec executor of the co-simulation: compiles project.st with iec2c, links the generated C with a generated
accessor harness into a shared library, and drives it cycle by cycle through ctypes (the path a user with OpenPLC has)."""

from __future__ import annotations

import ctypes
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Callable

from transpiler.backends.iec_model import IecProject
from transpiler.backends.report.iomap import Place
from transpiler.backends.st.check import matiec_home
from transpiler.exec.st_lines import loop_sites
from transpiler.exec.compiled.sysfb import HARNESS_C, SysBinding, patch_pous

SCALARS = {"BOOL": "BOOL", "SINT": "SINT", "INT": "INT", "DINT": "DINT", "LINT": "LINT", "USINT": "USINT",
           "UINT": "UINT", "UDINT": "UDINT", "BYTE": "BYTE", "WORD": "WORD", "DWORD": "DWORD"}
TIMEOUT_S = 300


class MatiecBuildError(Exception):
    pass


def _cache_dir() -> Path:
    base = os.environ.get("HH2IEC_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "hh2iec")
    return Path(base) / "matiec"


def _variables(project: IecProject) -> list[tuple[str, str, str, str]]:
    """(path, element type, 'scalar'|'array'|'string'|'string_array', C pointer) of every configuration global the
    harness can reach, and of every scalar or string member of a STRUCT global (path `VAR.MEMBER`, upper case as
    matiec names it); the pointer is C code that points at the value (the array, the string)."""
    arrays = {t.name.upper(): t for t in project.types if t.kind == "array"}
    structs = {t.name.upper(): t for t in project.types if t.kind == "struct"}
    out = []

    def add(path: str, typ: str, pointer: str) -> None:
        if typ in SCALARS:
            out.append((path, typ, "scalar", pointer))
        elif typ == "STRING":
            out.append((path, "STRING", "string", pointer))
        elif typ in arrays and (arrays[typ].base or "").upper() in SCALARS:
            out.append((path, arrays[typ].base.upper(), "array", pointer))
        elif typ in arrays and (arrays[typ].base or "").upper() == "STRING":
            out.append((path, "STRING", "string_array", pointer))

    for section in project.configuration.globals:
        for v in section.vars:
            name, typ = v.name.upper(), v.type.upper()
            if typ in structs:
                for field in structs[typ].fields:
                    member = field.name.upper()
                    if field.type.upper() in SCALARS or field.type.upper() == "STRING":
                        add(f"{name}.{member}", field.type.upper(), f"(&__GET_GLOBAL_{name}()->{member})")
            else:
                add(name, typ, f"__GET_GLOBAL_{name}()")
    return out


def harness_source(project: IecProject) -> str:
    """C glue: located storage, init/run with the simulated clock, and get/set of every global by number."""
    located = [v.address for s in project.configuration.globals for v in s.vars if v.address]
    lines = ['#include <string.h>', '#include "iec_std_lib.h"', '#include "POUS.h"',
             f'#include "{project.configuration.name}.h"', "",
             "TIME __CURRENT_TIME;", "BOOL __DEBUG = 0;", "extern unsigned long long common_ticktime__;",
             "void config_init__(void);", "void config_run__(unsigned long tick);", "static unsigned long hh_tick;", ""]
    types = {v.address: v.type.upper() for s in project.configuration.globals for v in s.vars if v.address}
    for address in located:
        c = "__" + address[1:].replace(".", "_")
        lines.append(f"static {SCALARS.get(types[address], 'BOOL')} {c}_store;")
        lines.append(f"{SCALARS.get(types[address], 'BOOL')} *{c} = &{c}_store;")
    lines += ["", "void hh_init(void) {"]
    for address in located:
        c = "__" + address[1:].replace(".", "_")
        lines.append(f"    memset(&{c}_store, 0, sizeof {c}_store);")
    lines += ["    __CURRENT_TIME.tv_sec = 0;", "    __CURRENT_TIME.tv_nsec = 0;", "    hh_tick = 0;",
              "    config_init__();", "}", "",
              "void hh_run(void) {", "    config_run__(hh_tick++);",
              "    __CURRENT_TIME.tv_nsec += common_ticktime__;",
              "    while (__CURRENT_TIME.tv_nsec >= 1000000000) {",
              "        __CURRENT_TIME.tv_nsec -= 1000000000;", "        __CURRENT_TIME.tv_sec++;", "    }", "}", ""]
    variables = _variables(project)
    get = ["long long hh_get(int id, int index) {", "    switch (id) {"]
    put = ["void hh_set(int id, int index, long long value) {", "    switch (id) {"]
    sget = ["int hh_get_str(int id, int index, char *out) {", "    IEC_STRING *s = 0;", "    switch (id) {"]
    sput = ["void hh_set_str(int id, int index, const char *text) {", "    IEC_STRING *s = 0;", "    switch (id) {"]
    for n, (_, typ, shape, pointer) in enumerate(variables):
        if shape == "scalar":
            get.append(f"    case {n}: return (long long)*{pointer};")
            put.append(f"    case {n}: *{pointer} = ({typ})value; break;")
        elif shape == "array":
            get.append(f"    case {n}: return (long long){pointer}->table[index];")
            put.append(f"    case {n}: {pointer}->table[index] = ({typ})value; break;")
        elif shape == "string":
            sget.append(f"    case {n}: s = {pointer}; break;")
            sput.append(f"    case {n}: s = {pointer}; break;")
        else:
            sget.append(f"    case {n}: s = &{pointer}->table[index]; break;")
            sput.append(f"    case {n}: s = &{pointer}->table[index]; break;")
    get += ["    }", "    return 0;", "}", ""]
    put += ["    }", "}", ""]
    sget += ["    }", "    if (!s) return -1;", "    memcpy(out, s->body, s->len);", "    out[s->len] = 0;",
             "    return s->len;", "}", ""]
    sput += ["    }", "    if (!s) return;", "    size_t n = strlen(text);", "    if (n > STR_MAX_LEN) n = STR_MAX_LEN;",
             "    memcpy(s->body, text, n);", "    s->len = (__strlen_t)n;", "}", ""]
    return "\n".join(lines + get + put + sget + sput + BULK_READ + GUARDED_RUN + HARNESS_C)


# One call per cycle reads every compared operand: a column is (variable id, index, width, big endian); width 0 reads
# the variable, 1/2/4 combines that many bytes of a byte array into a signed value.
BULK_READ = [
    "void hh_get_many(int n, const int *columns, long long *out) {",
    "    for (int i = 0; i < n; i++) {",
    "        const int *c = columns + 4 * i;",
    "        int width = c[2];",
    "        if (width == 0) { out[i] = hh_get(c[0], c[1]); continue; }",
    "        unsigned long long v = 0;",
    "        for (int k = 0; k < width; k++) {",
    "            int offset = c[3] ? width - 1 - k : k;",
    "            v |= ((unsigned long long)hh_get(c[0], c[1] + offset) & 0xFFu) << (8 * k);",
    "        }",
    "        unsigned long long sign = 1ULL << (8 * width - 1);",
    "        out[i] = (long long)((v ^ sign) - sign);",
    "    }",
    "}", ""]


# A cycle of compiled ST cannot be interrupted from Python (ctypes holds the thread), so an endless loop in the
# translation would hang the co-simulation. The cycle runs under a real-time alarm instead: when it fires, the
# handler jumps back out of the generated code and the run ends with a finding (the state is abandoned).
GUARDED_RUN = [
    "#include <setjmp.h>", "#include <signal.h>", "#include <sys/time.h>",
    "static sigjmp_buf hh_escape;",
    "static volatile sig_atomic_t hh_guarded;",
    "static void hh_alarm(int sig) { (void)sig; if (hh_guarded) siglongjmp(hh_escape, 1); }",
    "int hh_run_guarded(long budget_ms) {",
    "    struct sigaction action, previous;",
    "    struct itimerval start, stop;",
    "    memset(&action, 0, sizeof action);",
    "    memset(&start, 0, sizeof start);",
    "    memset(&stop, 0, sizeof stop);",
    "    action.sa_handler = hh_alarm;",
    "    sigemptyset(&action.sa_mask);",
    "    start.it_value.tv_sec = budget_ms / 1000;",
    "    start.it_value.tv_usec = (budget_ms % 1000) * 1000;",
    "    sigaction(SIGALRM, &action, &previous);",
    "    if (sigsetjmp(hh_escape, 1)) {",
    "        hh_guarded = 0;",
    "        setitimer(ITIMER_REAL, &stop, 0);",
    "        sigaction(SIGALRM, &previous, 0);",
    "        return 1;",
    "    }",
    "    hh_guarded = 1;",
    "    setitimer(ITIMER_REAL, &start, 0);",
    "    hh_run();",
    "    hh_guarded = 0;",
    "    setitimer(ITIMER_REAL, &stop, 0);",
    "    sigaction(SIGALRM, &previous, 0);",
    "    return 0;",
    "}", ""]

CYCLE_BUDGET_MS = 2000      # a PLC cycle of the translation takes microseconds; 2 s means it never ends


class CycleOverrun(RuntimeError):
    """A cycle of the compiled translation did not end within the budget (an endless loop)."""


def build_library(st_text: str, project: IecProject, iec2c: Path, extra_c: str = "") -> Path:
    """Compile once per distinct ST text (cached by hash); raises MatiecBuildError with the tool's message.
    `extra_c` is more C for the harness (the accessors of a mutant schema's globals)."""
    home = matiec_home(iec2c)
    harness = harness_source(project) + extra_c
    # The harness is part of the key: a changed harness must not reuse a library built from an older one.
    digest = hashlib.sha256((st_text + str(iec2c) + harness).encode("utf-8")).hexdigest()[:20]
    folder = _cache_dir() / digest
    lib = folder / "libhhplc.so"
    if lib.is_file():
        return lib
    folder.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="build-", dir=folder.parent))
    (work / "project.st").write_text(st_text, encoding="utf-8")
    gen = work / "gen"
    gen.mkdir()
    run = subprocess.run([str(iec2c), "-I", str(home / "lib"), "-T", str(gen), str(work / "project.st")],
                         capture_output=True, text=True, timeout=TIMEOUT_S)
    if run.returncode != 0:
        shutil.rmtree(work, ignore_errors=True)
        raise MatiecBuildError(f"iec2c failed: {(run.stdout + run.stderr).strip()[:2000]}")
    (gen / "hh_harness.c").write_text(harness, encoding="utf-8")
    pous = gen / "POUS.c"
    if pous.is_file():      # the HH_Sys FBs run the shim's model (sysfb.py)
        pous.write_text(patch_pous(pous.read_text(encoding="utf-8"), SysBinding(st_text).c_bodies()), encoding="utf-8")
    sources = [str(gen / "hh_harness.c")] + sorted(str(p) for p in gen.glob("*.c")
                                                   if p.name not in ("POUS.c", "hh_harness.c"))
    cc = subprocess.run(["gcc", "-shared", "-fPIC", "-O1", "-fwrapv", "-Wno-unused-function", "-w",
                         f"-I{home / 'lib' / 'C'}", f"-I{gen}", "-o", str(work / "libhhplc.so"), *sources, "-lm"],
                        capture_output=True, text=True, timeout=TIMEOUT_S)
    if cc.returncode != 0:
        shutil.rmtree(work, ignore_errors=True)
        raise MatiecBuildError(f"gcc failed on the matiec output: {cc.stderr.strip()[:2000]}")
    try:
        os.replace(work, folder)
    except OSError:
        if not lib.is_file():          # a concurrent build may have won the race; otherwise report
            raise MatiecBuildError(f"cannot store the build in {folder}") from None
    return lib


def bind_sys(lib: ctypes.CDLL, sys: SysBinding, machine: object) -> None:
    """The HH_Sys FBs of the library call the shim's model on a copy of the machine's system context."""
    sys.attach(machine)
    fn, handle, rule = sys.call_pointer()
    lib.hh_sysfb_bind(ctypes.c_void_p(fn), ctypes.c_void_p(handle), rule)


def matiec_side_factory(st_text: str, project: IecProject, iec2c: Path) -> Callable[[], object]:
    """Build the library once; each call gives the program re-initialised (config_init__, cleared I/O)."""
    return sides_of(load_library(build_library(st_text, project, iec2c)), st_text, project)


def load_library(lib_path: Path) -> ctypes.CDLL:
    """The built library loaded, its harness functions typed for ctypes."""
    lib = ctypes.CDLL(str(lib_path))
    lib.hh_get.restype = ctypes.c_longlong
    lib.hh_get.argtypes = [ctypes.c_int, ctypes.c_int]
    lib.hh_set.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_longlong]
    lib.hh_get_str.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p]
    lib.hh_set_str.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p]
    lib.hh_get_many.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_longlong)]
    lib.hh_run_guarded.argtypes = [ctypes.c_long]
    lib.hh_run_guarded.restype = ctypes.c_int
    return lib


def sides_of(lib: ctypes.CDLL, st_text: str, project: IecProject,
           start: Callable[[], None] | None = None, infected: Callable[[], set[int]] | None = None
           ) -> Callable[[], object]:
    # Kept whole (~83 lines): the side class closes over the loaded library, its variable ids and buffers.
    """The side class over a loaded library: `start` runs after each re-initialisation (a schema sets its mutant
    number), `infected` reads the mutants a probing run infected (a schema's PROBE sides only)."""
    loops = loop_sites(st_text)
    variables = _variables(project)
    ids = {path: (n, typ, shape) for n, (path, typ, shape, _) in enumerate(variables)}
    buffer = ctypes.create_string_buffer(512)

    located: dict[str, tuple[int, int, str, str]] = {}

    def locate(path: str) -> tuple[int, int, str, str]:
        found = located.get(path)
        if found is None:
            found = located[path] = _locate(path)
        return found

    def _locate(path: str) -> tuple[int, int, str, str]:
        m = re.fullmatch(r"(\w+(?:\.\w+)?)(?:\[(-?\d+)\])?", path.strip())
        if m is None or m.group(1).upper() not in ids:
            raise KeyError(path)
        n, typ, shape = ids[m.group(1).upper()]
        return n, int(m.group(2) or 0), typ, shape

    class _Side:
        name = "matiec"

        def __init__(self) -> None:
            lib.hh_init()
            if start is not None:
                start()
            self.sys = SysBinding(st_text)
            self.attach_machine = lambda machine: bind_sys(lib, self.sys, machine)

        def get(self, path: str):
            n, index, typ, shape = locate(path)
            if shape.startswith("string"):
                length = lib.hh_get_str(n, index, buffer)
                return buffer.raw[:max(length, 0)].decode("latin-1")
            value = lib.hh_get(n, index)
            return bool(value) if typ == "BOOL" else int(value)

        def set(self, path: str, value) -> None:
            n, index, typ, shape = locate(path)
            if shape.startswith("string"):
                lib.hh_set_str(n, index, str(value).encode("latin-1", "replace"))
            else:
                lib.hh_set(n, index, int(value))

        def run_cycle(self) -> None:
            if lib.hh_run_guarded(CYCLE_BUDGET_MS):
                raise CycleOverrun(f"the cycle did not end within {CYCLE_BUDGET_MS / 1000:g} s (an endless loop); "
                                   "the ST lines that loop: " + ", ".join(loops or ["none found"]))
            self.sys.tick()

        @property
        def infected(self) -> set[int]:
            """The mutants this (probing) run has infected so far."""
            return infected() if infected is not None else set()

        def bulk_reader(self, places: list[Place]) -> Callable[[], list]:
            """Reads all places in one C call (texts, which C cannot return as numbers, one by one)."""
            spec = (ctypes.c_int * (4 * len(places)))()
            texts = []
            for i, place in enumerate(places):
                if place.text:
                    texts.append((i, place.path))
                    continue
                n, index, _, _ = locate(place.path)
                spec[4 * i:4 * i + 4] = [n, index, place.width, int(place.big_endian)]
            out = (ctypes.c_longlong * len(places))()
            count = len(places)

            def read() -> list:
                lib.hh_get_many(count, spec, out)
                values = out[:]
                for i, path in texts:
                    values[i] = self.get(path)
                return values
            return read

    return _Side
