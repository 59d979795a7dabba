"""The OpenPLC v3 runtime's own program build and run, on hh2iec's `--target openplc` output (opt-in: OPENPLC_HOME).

OPENPLC_HOME is an OpenPLC_v3 checkout in which the pieces its installer builds have been built in place (nothing
of it is copied into this repository or installed system-wide):

    utils/matiec_src        autoreconf -i && ./configure && make          (the runtime's own iec2c)
    utils/libmodbus_src     ./autogen.sh && ./configure && make           (its libmodbus fork; or set
                            OPENPLC_LIBMODBUS to an install prefix holding include/modbus and lib)
    utils/snap7_src/build/linux   make                                    (libsnap7.so)

A program is built as the runtime's `webserver/scripts/compile_program.sh` builds an upload on the linux platform
with the blank hardware layer, in a scratch copy of `webserver/core`: `iec2c -f -l -p -r -R -a` on the .st, the
generated files moved into core under their fixed names, `g++ -std=gnu++11 -I ./lib -c Config0.c` and `Res0.c`,
the glue generator, the link with libmodbus and snap7 (DNP3 left out as on platforms without opendnp3: its dummy
is linked instead). The run starts the runtime, turns its Modbus TCP server on through the interactive server
(127.0.0.1:43628) and reads the coils (%QX) from 127.0.0.1, in a private network namespace when `unshare` can
make one (the runtime's Modbus server listens on every interface).

The comparison, over the same time from a power-on with all inputs low and no NC (the runtime has none: nothing
pulses the first-cycle marker or writes an NC operand): the built-in ST executor runs the translated ST exactly as
written, and every output it holds steady over the whole window of the reads must have that value in every read.
The reference interpreter runs the original program under the same conditions, and every output both hold steady
must agree, except where the translation calls PLC-module blocks the target must provide: on the runtime those are
the stubs of the ST (they report a fault until implemented), so such differences are listed as theirs, not
failures (with the modules modelled, `equiv` proves the ST equal to the original). Outputs that change inside the
window are counted, not compared; a program that faults under that power-on (an index its inputs must set first)
is built and not compared, and its verdict says why.

    python -m tests.openplc_runtime --measure    # build every snippet of tests/data/openplc_verdicts and every
                                                 # sample project, run the projects, rewrite the recorded verdicts
    python -m tests.openplc_runtime --check      # the same, compared with the recorded verdicts (exit 1 on a change)
    python -m tests.openplc_runtime --random 20 --seed 3   # 20 random projects of the differential tester
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DATA_DIR = REPO / "tests" / "data" / "openplc_verdicts"
SNIPPET_VERDICTS = DATA_DIR / "verdicts.json"
PROJECT_VERDICTS = DATA_DIR / "projects.json"
# A snippet named unsafe_*: the build accepts it, but the program does not fit the runtime (its glue writes past the
# I/O image); the built-in rules must reject it all the same.
UNSAFE_PREFIX = "unsafe_"
GENERATED = ("POUS.c", "POUS.h", "LOCATED_VARIABLES.h", "VARIABLES.csv", "Config0.c", "Config0.h", "Res0.c")
CONTROL_PORT, MODBUS_PORT = 43628, 5020
# The reads: from READ_FROM seconds after start to READ_UNTIL, every READ_EVERY; the reference runs RUN_SECONDS.
READ_FROM, READ_UNTIL, READ_EVERY, RUN_SECONDS = 2.0, 4.0, 0.5, 6.0
# The runtime may start scanning this much later than its process (the reference's window starts this much earlier).
START_SLACK = 1.0
STEP_TIMEOUT = 600


@dataclasses.dataclass(frozen=True)
class OpenPlcHome:
    root: Path
    iec2c: Path
    iec_lib: Path
    core: Path
    glue_source: Path
    snap7_wrapper: Path
    snap7_lib: Path
    modbus_include: Path
    modbus_lib: Path

    def commit(self) -> str:
        try:
            out = subprocess.run(["git", "-C", str(self.root), "rev-parse", "--short", "HEAD"], capture_output=True,
                                 text=True, timeout=30, check=False).stdout.strip()
        except OSError:
            out = ""
        return out or "unknown"


def find_home(root: str | None = None) -> tuple[OpenPlcHome | None, str]:
    """The OpenPLC checkout named by `root` or $OPENPLC_HOME, or None and why it cannot be used."""
    root = root or os.environ.get("OPENPLC_HOME", "")
    if not root:
        return None, "OPENPLC_HOME is not set"
    base = Path(root).resolve()
    prefix = os.environ.get("OPENPLC_LIBMODBUS", "")
    modbus_include, modbus_lib = ((Path(prefix) / "include" / "modbus", Path(prefix) / "lib") if prefix else
                                  (base / "utils/libmodbus_src/src", base / "utils/libmodbus_src/src/.libs"))
    home = OpenPlcHome(base, base / "utils/matiec_src/iec2c", base / "webserver/lib", base / "webserver/core",
                       base / "utils/glue_generator_src/glue_generator.cpp", base / "utils/snap7_src/wrapper",
                       base / "utils/snap7_src/build/bin/linux", modbus_include, modbus_lib)
    needed = {"the runtime's iec2c (build utils/matiec_src)": home.iec2c,
              "webserver/lib": home.iec_lib / "IEC_std_lib.txt" if (home.iec_lib / "IEC_std_lib.txt").exists()
              else home.iec_lib,
              "webserver/core": home.core / "main.cpp",
              "the glue generator's source": home.glue_source,
              "libsnap7.so (make in utils/snap7_src/build/linux)": home.snap7_lib / "libsnap7.so",
              "libmodbus (build utils/libmodbus_src, or set OPENPLC_LIBMODBUS)": home.modbus_lib,
              "modbus.h": home.modbus_include / "modbus.h"}
    missing = [f"{what} ({path})" for what, path in needed.items() if not path.exists()]
    if missing:
        return None, f"OPENPLC_HOME={base} lacks: " + "; ".join(missing)
    return home, ""


@dataclasses.dataclass(frozen=True)
class Build:
    ok: bool
    step: str               # the step that failed ("" when the build succeeded)
    message: str            # its first error line, without paths
    folder: Path            # the scratch runtime folder (core/openplc inside when ok)


def _run(cmd: list[str], cwd: Path, env: dict | None = None) -> tuple[int, str]:
    try:
        done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=STEP_TIMEOUT, env=env, check=False)
    except subprocess.TimeoutExpired:
        return 124, f"timed out after {STEP_TIMEOUT} s"
    return done.returncode, done.stdout + done.stderr


def _first_error(output: str, *folders: Path) -> str:
    lines = [line for line in output.splitlines() if line.strip()]
    chosen = next((line for line in lines if re.search(r"error|Error|ERROR|cannot|No such", line)),
                  lines[-1] if lines else "")
    for folder in folders:
        chosen = chosen.replace(str(folder) + os.sep, "").replace(str(folder), "")
    return re.sub(r"(?<![\w.])/[^\s:]*/", "", chosen).strip()


def _glue_generator(home: OpenPlcHome, cache: Path) -> Path:
    binary = cache / "glue_generator"
    if not binary.exists():
        code, out = _run(["g++", "-std=gnu++11", str(home.glue_source), "-o", str(binary)], cache)
        if code != 0:
            raise RuntimeError(f"the glue generator does not build: {_first_error(out)}")
    return binary


def build_program(home: OpenPlcHome, st_text: str, work: Path, cache: Path) -> Build:
    """Build `st_text` as the runtime builds an upload, in `work` (created); see the module docstring."""
    shutil.copytree(home.core, work / "core", symlinks=True)
    (work / "lib").symlink_to(home.iec_lib)
    (work / "st_files").mkdir()
    # The web upload drops these lines before it compiles (they steer the runtime's debugger).
    kept = "\n".join(line for line in st_text.splitlines() if not line.startswith(("(*DBG:", "(*FILE:")))
    (work / "st_files" / "program.st").write_text(kept + "\n", encoding="utf-8")
    core = work / "core"
    shutil.copy(core / "hardware_layers" / "blank.cpp", core / "hardware_layer.cpp")
    (core / "dnp3.cpp").rename(core / "dnp3.disabled")
    (core / "dnp3_dummy.disabled").rename(core / "dnp3_dummy.cpp")
    code, out = _run([str(home.iec2c), "-f", "-l", "-p", "-r", "-R", "-a", "./st_files/program.st"], work)
    if code != 0:
        return Build(False, "iec2c", _first_error(out, work), work)
    for wrapper in home.snap7_wrapper.glob("oplc_snap7.*"):
        shutil.copy(wrapper, core)
    missing = [name for name in GENERATED if not (work / name).exists()]
    if missing:
        return Build(False, "move", f"mv: cannot stat '{missing[0]}': No such file or directory", work)
    for name in GENERATED:
        shutil.move(str(work / name), str(core / name))
    for unit in ("Config0.c", "Res0.c"):
        code, out = _run(["g++", "-std=gnu++11", "-I", "./lib", "-c", unit, "-w"], core)
        if code != 0:
            return Build(False, f"g++ {unit}", _first_error(out, work), work)
    shutil.copy(_glue_generator(home, cache), core / "glue_generator")
    code, out = _run(["./glue_generator"], core)
    if code != 0 or "Invalid addressing" in out:
        return Build(False, "glue_generator", _first_error(out, work), work)
    units = sorted(p.name for p in core.glob("*.cpp")) + ["Config0.o", "Res0.o"]
    code, out = _run(["g++", "-std=gnu++11", *units, "-o", "openplc", "-I", "./lib", "-pthread", "-fpermissive",
                      f"-I{home.modbus_include}", f"-L{home.modbus_lib}", "-lmodbus", f"-L{home.snap7_lib}", "-lsnap7",
                      "-lrt", "-w"], core)
    if code != 0:
        return Build(False, "link", _first_error(out, work), work)
    return Build(True, "", "", work)


# ---- running the runtime and reading its coils

def _control(command: str) -> bytes:
    with socket.create_connection(("127.0.0.1", CONTROL_PORT), timeout=3) as s:
        s.sendall(command.encode() + b"\n")
        try:
            return s.recv(1000)
        except OSError:
            return b""


def _read_coils(count: int, transaction: int) -> list[int]:
    """Modbus TCP function 1 (read coils) from coil 0, unit 1."""
    values: list[int] = []
    for start in range(0, count, 2000):
        n = min(2000, count - start)
        pdu = struct.pack(">BHH", 1, start, n)
        with socket.create_connection(("127.0.0.1", MODBUS_PORT), timeout=3) as s:
            s.sendall(struct.pack(">HHHB", transaction & 0xFFFF, 0, len(pdu) + 1, 1) + pdu)
            reply = b""
            while len(reply) < 9 or len(reply) < 9 + reply[8]:
                chunk = s.recv(4096)
                if not chunk:
                    break
                reply += chunk
        if len(reply) < 9 or reply[7] != 1:
            raise RuntimeError(f"unexpected Modbus reply {reply.hex()}")
        bits = reply[9:9 + reply[8]]
        values += [(bits[i // 8] >> (i % 8)) & 1 for i in range(n)]
    return values


def read_outputs(folder: Path, coils: int, env: dict) -> list[tuple[float, list[int]]]:
    """Start the runtime built in `folder`, turn on Modbus, read `coils` coils at the planned times; each read as
    (seconds since start, values). The runtime is stopped (quit(), then killed) whatever happens."""
    log = open(folder / "runtime.log", "wb")
    process = subprocess.Popen(["./core/openplc"], cwd=folder, env=env, stdout=log, stderr=subprocess.STDOUT)
    started = time.monotonic()
    reads: list[tuple[float, list[int]]] = []
    try:
        deadline = started + 10
        while True:
            try:
                if _control(f"start_modbus({MODBUS_PORT})").startswith(b"OK"):
                    break
            except OSError:
                pass
            if time.monotonic() > deadline or process.poll() is not None:
                raise RuntimeError("the runtime did not answer on its interactive server")
            time.sleep(0.1)
        when = READ_FROM
        while when <= READ_UNTIL + 1e-9:
            time.sleep(max(0.0, started + when - time.monotonic()))
            for attempt in range(20):
                try:
                    reads.append((time.monotonic() - started, _read_coils(coils, len(reads) + 1)))
                    break
                except OSError:
                    if attempt == 19:
                        raise
                    time.sleep(0.05)
            when += READ_EVERY
    finally:
        try:
            _control("quit()")
        except OSError:
            pass
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        log.close()
    return reads


def run_and_read(home: OpenPlcHome, folder: Path, coils: int) -> list[tuple[float, list[int]]]:
    """read_outputs, in a private network namespace (loopback only) where `unshare` can make one."""
    env = {**os.environ, "LD_LIBRARY_PATH": f"{home.modbus_lib}:{home.snap7_lib}"}
    inner = [sys.executable, "-m", "tests.openplc_runtime", "--read", str(folder), str(coils)]
    unshare = shutil.which("unshare")
    if unshare is not None and shutil.which("ip") is not None and \
            subprocess.run([unshare, "-n", "true"], capture_output=True, check=False).returncode == 0:
        cmd = [unshare, "-n", "sh", "-c", 'ip link set lo up && exec "$@"', "sh", *inner]
    else:
        cmd = inner
    done = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=120, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"running the runtime failed: {done.stderr.strip()[-500:]}")
    return [(t, values) for t, values in json.loads(done.stdout)]


# ---- the projects and their reference

def sample_projects() -> list[Path]:
    """Every sample project: the Basic-Program-style sample, modules_demo and each construct."""
    constructs = sorted(p for p in (REPO / "samples" / "constructs").iterdir() if p.is_dir())
    return [REPO / "samples" / "basic_program", REPO / "samples" / "modules_demo", *constructs]


def project_key(folder: Path) -> str:
    return folder.resolve().relative_to(REPO).as_posix()


@dataclasses.dataclass
class Reference:
    st_text: str
    coils: dict[int, str]                 # coil number -> operand name, for every output the program uses
    steady: dict[int, int]                # coil -> its value, for outputs the original holds over the read window
    changing: list[int]
    fault: str = ""                       # the original's fault, when it faults before the reads end
    st_steady: dict[int, int] = dataclasses.field(default_factory=dict)   # the same for the ST as written
    stubs: tuple[str, ...] = ()           # the PLC-module blocks the target must provide (stubs in the ST)


def random_projects(count: int, seed: int, root: Path) -> list[tuple[str, Path, Path | None]]:
    """`count` random projects of the differential tester (programs nobody wrote for this check), written under
    `root`: (name, main program, configuration file or None)."""
    from tests.difftest.generator import generate
    projects = []
    for index in range(count):
        generated = generate(seed * 1_000_000 + index)
        folder = root / f"random_{generated.seed}"
        generated.write(folder)
        projects.append((f"random:{generated.seed}", folder / generated.main,
                         folder / generated.cfg if generated.cfg else None))
    return projects


def reference(folder: Path, cfg: Path | None = None) -> Reference:
    """The openplc translation of `folder` (a project folder or its main program; `cfg` its configuration file),
    and the reference's outputs over the run (see the module docstring)."""
    from transpiler import api
    from transpiler.backends.st.hh_sys import fb_names
    from transpiler.verify.simulate import program_operands
    project = api.load_project(api.project_options(folder, cfg=cfg))
    translation = api.transpile(project, target="openplc", validate_xml=False, formats=("st",))
    used, _, outputs = program_operands(project.program)
    semantics = project.program.semantics
    cycle_ms = int(semantics["cycle_time_ms"])
    # No NC pulses the first-cycle marker on the runtime: the reference moves the pulse onto a marker the program
    # never names, so that its first cycle is the runtime's.
    named = {ref.addr for ref in used if ref.kind == "M"}
    lo, hi = max(semantics.profile.ranges.M, key=lambda r: r[1])
    spare = next(m for m in range(hi, lo - 1, -1) if m != int(semantics["first_cycle_marker"]) and m not in named)
    cycles = int(RUN_SECONDS * 1000 / cycle_ms)
    lines = [f"cycles: {cycles}", f"cycle_time_ms: {cycle_ms}"]
    if translation.mp_file is not None:
        lines.append(f"machine_parameters: {json.dumps(str(Path(translation.mp_file).resolve()))}")
    outputs = sorted(outputs)
    if outputs:
        lines.append("observe: [" + ", ".join(f"O{ref.addr}" for ref in outputs) + "]")
    with tempfile.TemporaryDirectory(prefix="openplc_ref_") as tmp:
        scenario = Path(tmp) / "power_on.yaml"
        scenario.write_text("\n".join(lines) + "\n", encoding="utf-8")
        # A scenario's semantics apply when the project is loaded (as `simulate` does on the command line).
        silent_nc = api.load_project(project.options, api.semantics_for(
            semantics.profile.name, {"first_cycle_marker": spare}))
        run = api.simulate(silent_nc, scenario).run
    st_text = translation.files["project.st"].decode("utf-8")
    if run.fault is not None:
        # A program that faults from power-on with every input low (an index the inputs must set first) has no
        # steady state to compare: the build is still checked, the outputs are not.
        return Reference(st_text, {}, {}, [], f"{run.fault.code} in cycle {run.fault.cycle}: {run.fault.message}")
    window = slice(max(0, int((READ_FROM - START_SLACK) * 1000 / cycle_ms)),
                   min(cycles, int((READ_UNTIL + START_SLACK) * 1000 / cycle_ms) + 1))
    coils = {ref.addr: name for name, ref in run.trace.columns if ref.kind == "O"}
    steady, changing = _steady({addr: run.trace.column(name)[window] for addr, name in coils.items()})
    stubs = tuple(sorted(p.name for p in translation.result.project.pous if p.name.upper() in fb_names()))
    return Reference(st_text, coils, steady, changing, st_steady=_st_outputs(st_text, cycles, coils, window),
                     stubs=stubs)


def _steady(values: dict[int, list]) -> tuple[dict[int, int], list[int]]:
    """(coil -> value for the coils whose values are all one, the coils whose values change)."""
    steady = {coil: int(seen[0]) for coil, seen in values.items() if len({int(v) for v in seen}) == 1}
    return steady, sorted(set(values) - set(steady))


def _st_outputs(st_text: str, cycles: int, coils: dict[int, str], window: slice) -> dict[int, int]:
    """The outputs the built-in ST executor holds steady over `window` running `st_text` exactly as written (the
    PLC-module blocks as the stubs they are there, nothing writing the NC variables): what the runtime must show.
    Empty when the ST faults."""
    from transpiler.exec.stexec import StRuntimeError, load_st
    runtime = load_st(st_text, "project.st").instantiate()
    addresses = {coil: f"%QX{coil // 8}.{coil % 8}" for coil in coils}
    seen: dict[int, list] = {coil: [] for coil in coils}
    try:
        for _ in range(cycles):
            runtime.run_cycle()
            for coil, address in addresses.items():
                seen[coil].append(int(runtime.get(address)))
    except StRuntimeError:
        return {}
    return _steady({coil: values[window] for coil, values in seen.items()})[0]


def check_project(home: OpenPlcHome, folder: Path, scratch: Path, cache: Path, cfg: Path | None = None) -> dict:
    """Build and run `folder`'s translation on the runtime; the verdict as recorded in projects.json.

    Every output the ST (run as written by the built-in executor) holds steady over the reads must read the same on
    the runtime (`mismatches`: the runtime runs the ST otherwise). Where the original program holds the output steady
    too, the two must agree, except where the translation calls PLC-module blocks the target must provide, which
    are stubs until then (`module_stub_differences`, listed, not failures)."""
    ref = reference(folder, cfg)
    build = build_program(home, ref.st_text, scratch, cache)
    verdict = {"build": build.ok, "failed_step": build.step, "message": build.message,
               "outputs": len(ref.coils), "compared": 0, "changing": len(ref.changing), "mismatches": [],
               "reference_fault": ref.fault, "module_stubs": list(ref.stubs), "module_stub_differences": []}
    if not build.ok or not ref.coils or not ref.st_steady:
        return verdict

    def where(coil: int) -> str:
        return f"{ref.coils[coil]} (%QX{coil // 8}.{coil % 8})"
    reads = run_and_read(home, build.folder, max(ref.coils) + 1)
    mismatches = []
    for coil, value in sorted(ref.st_steady.items()):
        seen = sorted({values[coil] for _, values in reads})
        if seen != [value]:
            mismatches.append(f"{where(coil)}: the ST as written {value}, runtime {seen}")
    differences = [f"{where(coil)}: original {ref.steady[coil]}, the ST as written {value}"
                   for coil, value in sorted(ref.st_steady.items())
                   if coil in ref.steady and ref.steady[coil] != value]
    if ref.stubs:
        verdict["module_stub_differences"] = differences
    else:
        mismatches += differences
    verdict.update(compared=len(ref.st_steady), reads=len(reads), mismatches=mismatches)
    return verdict


def measure_snippet(home: OpenPlcHome, text: str, scratch: Path, cache: Path) -> dict:
    build = build_program(home, text, scratch, cache)
    return {"accept": build.ok, "failed_step": build.step, "message": build.message}


def _summary(key: str, v: dict) -> str:
    return (f"project {key}: build {'ok' if v['build'] else 'FAILED at ' + v['failed_step']}"
            f"{', ' + v['message'] if v['message'] else ''}; {v['compared']} of {v['outputs']} outputs compared "
            f"({v['changing']} changing in the original), {len(v['mismatches'])} mismatches"
            f"{'; ' + str(len(v['module_stub_differences'])) + ' differ from the original by the module stubs ' + ', '.join(v['module_stubs']) if v['module_stub_differences'] else ''}"
            f"{'; not compared, the reference faults: ' + v['reference_fault'] if v['reference_fault'] else ''}")


def _random_run(home: OpenPlcHome, count: int, seed: int) -> int:
    failed = 0
    with tempfile.TemporaryDirectory(prefix="openplc_random_") as tmp:
        for key, main, cfg in random_projects(count, seed, Path(tmp) / "projects"):
            scratch = Path(tmp) / key.replace(":", "_")
            verdict = check_project(home, main, scratch, Path(tmp), cfg)
            print(_summary(key, verdict), flush=True)
            for line in verdict["mismatches"]:
                print(f"  {line}")
            failed += not verdict["build"] or bool(verdict["mismatches"])
    print(f"{count} random projects: {count - failed} built and matched, {failed} failed")
    return 1 if failed else 0


def _identity(home: OpenPlcHome) -> dict:
    return {"openplc_commit": home.commit(), "platform": "linux, blank hardware layer, no opendnp3"}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--measure", action="store_true", help="rewrite the recorded verdicts")
    mode.add_argument("--check", action="store_true", help="compare with the recorded verdicts")
    mode.add_argument("--random", type=int, metavar="N", help="build and run N random projects of the differential "
                      "tester instead (nothing recorded; exit 1 on a failure)")
    mode.add_argument("--read", nargs=2, metavar=("FOLDER", "COILS"), help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=1, help="seed of --random")
    parser.add_argument("--only", action="append", default=[], help="only this snippet or project key")
    args = parser.parse_args(argv)
    if args.read:
        print(json.dumps(read_outputs(Path(args.read[0]), int(args.read[1]), dict(os.environ))))
        return 0
    home, why = find_home()
    if home is None:
        print(f"openplc_runtime: {why}", file=sys.stderr)
        return 2
    if args.random:
        return _random_run(home, args.random, args.seed)
    snippets: dict[str, dict] = {}
    projects: dict[str, dict] = {}
    with tempfile.TemporaryDirectory(prefix="openplc_runtime_") as tmp:
        cache = Path(tmp)
        for path in sorted(DATA_DIR.glob("*.st")):
            if args.only and path.stem not in args.only:
                continue
            snippets[path.stem] = {**measure_snippet(home, path.read_text(encoding="utf-8"), cache / path.stem, cache),
                                   **_identity(home)}
            print(f"snippet {path.stem}: {'accepted' if snippets[path.stem]['accept'] else 'rejected'} "
                  f"{snippets[path.stem]['message']}", flush=True)
        for folder in sample_projects():
            key = project_key(folder)
            if args.only and key not in args.only:
                continue
            projects[key] = {**check_project(home, folder, cache / key.replace("/", "_"), cache), **_identity(home)}
            v = projects[key]
            print(_summary(key, v), flush=True)
            for line in v["mismatches"]:
                print(f"  {line}")
    if args.measure:
        old_snippets = json.loads(SNIPPET_VERDICTS.read_text()) if SNIPPET_VERDICTS.exists() and args.only else {}
        old_projects = json.loads(PROJECT_VERDICTS.read_text()) if PROJECT_VERDICTS.exists() and args.only else {}
        SNIPPET_VERDICTS.write_text(json.dumps({**old_snippets, **snippets}, indent=2, sort_keys=True) + "\n")
        PROJECT_VERDICTS.write_text(json.dumps({**old_projects, **projects}, indent=2, sort_keys=True) + "\n")
        return 0
    recorded_snippets = json.loads(SNIPPET_VERDICTS.read_text())
    recorded_projects = json.loads(PROJECT_VERDICTS.read_text())
    changed = [name for name, v in snippets.items()
               if recorded_snippets.get(name, {}).get("accept") != v["accept"]]
    changed += [key for key, v in projects.items()
                if (recorded_projects.get(key, {}).get("build"), bool(recorded_projects.get(key, {}).get("mismatches")))
                != (v["build"], bool(v["mismatches"]))]
    failing = [key for key, v in projects.items() if not v["build"] or v["mismatches"]]
    for name in changed:
        print(f"changed since recorded: {name}", file=sys.stderr)
    for key in failing:
        print(f"fails on the runtime: {key}", file=sys.stderr)
    return 1 if changed or failing else 0


if __name__ == "__main__":
    sys.exit(main())
