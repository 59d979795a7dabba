"""Front-end driver: configuration, preprocessing and parsing of every project file in the spec's order (1.3)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Iterator, Mapping

from transpiler.frontend import ast
from transpiler.diagnostics import Diagnostics, Span, NO_SPAN
from transpiler.frontend.mainfile import is_module
from transpiler.frontend.masks import read_masks
from transpiler.ir import Mask
from transpiler.frontend.parse import DefParser, SrcParser
from transpiler.frontend.preprocess import (DefineValue, Defines, InactiveRegion, PPParser, Preprocessor, find_default_cfg,
                         initial_defines, read_config, unused_overrides)
from transpiler.language.semantics import Semantics
from transpiler.frontend.sources import ProjectFolders, SourceText, read_source


MAX_DEF_NESTING = 64          # #define inside definition files


@dataclasses.dataclass(frozen=True)
class ParsedProject:
    """Every file of a project parsed, before symbol and label resolution."""

    src_files: tuple[ast.SourceFile, ...]          # [0] is the main program, then USES order (depth-first)
    global_defs: tuple[ast.DefFile, ...]
    local_defs: Mapping[str, tuple[ast.DefFile, ...]]   # src display path -> its local .def files
    defines: Mapping[str, DefineValue]
    inactive: tuple[InactiveRegion, ...]
    files_read: tuple[str, ...]
    line_count: int
    # Where a named file could not be read, the symbols or labels it would have provided are unknown; the
    # resolver then does not report their uses (one root error per fault, no cascade of E-SYM-UNDEF).
    # "*" stands for the global definitions (a missing `#define /g` file).
    symbols_incomplete: frozenset[str] = frozenset()
    labels_incomplete: bool = False
    number_mp4111: int | None = None     # DEFINE NUMBERMP4111 of the configuration, when set
    config_file: str | None = None       # display path of the configuration read
    masks: tuple[Mask, ...] = ()         # the screen masks beside the main program, references unresolved


MAX_NUMBER_MP4111 = 904             # T96 ... T999


@dataclasses.dataclass
class ProjectOptions:
    main: Path
    cfg: Path | None = None
    use_default_cfg: bool = True
    defines: Mapping[str, DefineValue] = dataclasses.field(default_factory=dict)
    include_dirs: tuple[Path, ...] = ()
    extra_global_defs: tuple[Path, ...] = ()
    encoding: str | None = None          # None: each file's own (UTF-8 when it decodes as UTF-8, else cp1252)
    werror: bool = False                 # warnings fail the run (E-WERROR)
    # PLC data tables given on the command line, by table name (MP_Data.tab, MP_Config.tab); the others are looked
    # for beside the main program (frontend/datatables.py)
    data_tables: Mapping[str, Path] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class Parsers:
    """The line parsers of one semantics. Their caches depend only on the line text, so one set may serve
    several runs with the same semantics (a fuzzer or an editor re-checking a project after each change)."""

    pp: PPParser
    src: SrcParser
    defs: DefParser

    @classmethod
    def for_semantics(cls, semantics: Semantics) -> "Parsers":
        documented = semantics["literal_range"] == "documented"
        return cls(PPParser(), SrcParser(bool(semantics["lenient_brackets"]), documented), DefParser(documented))


class _Loader:
    def __init__(self, options: ProjectOptions, semantics: Semantics, diags: Diagnostics, parsers: Parsers | None = None):
        self.options = options
        self.semantics = semantics
        self.diags = diags
        self.folders = ProjectFolders(options.main.parent, list(options.include_dirs))
        self.defines: Defines = initial_defines(options.defines, semantics["define_case"] == "insensitive")
        self.parsers = parsers or Parsers.for_semantics(semantics)
        self.inactive: list[InactiveRegion] = []
        self.files_read: list[str] = []
        self.line_count = 0
        self.symbols_incomplete: set[str] = set()
        self.labels_incomplete = False
        self._def_missing = False       # set by _load_def when a file of the current request is unreadable
        self.config_file: str | None = None

    def _read(self, path: Path, at: Span) -> SourceText | None:
        text = read_source(path, self.folders, at, self.diags, self.options.encoding)
        if text is not None:
            self.files_read.append(text.display)
            self.line_count += len(text.lines)
        return text

    def _preprocess(self, text: SourceText) -> list:
        pre = Preprocessor(self.defines, self.diags, self.parsers.pp)

        def include(name: str, at: Span):
            path = self.folders.find(name, at, self.diags, text.path.parent)
            if path is None:
                return None
            inc = self._read(path, at)
            return (inc.display, inc.lines) if inc else None

        lines = pre.run(text.display, text.lines, include, star_comments=bool(self.semantics["star_comments"]))
        self.inactive.extend(pre.inactive)
        return lines

    def load(self) -> ParsedProject:
        opts = self.options
        cfg = opts.cfg
        if cfg is None and opts.use_default_cfg:
            cfg = find_default_cfg(opts.main)
        if cfg is not None:
            # --cfg may name a file anywhere (it is given on the command line, not by the project); its display
            # path is relative to the main folder when it lies inside it, as for every other file.
            cfg_text = self._read(cfg, NO_SPAN)
            if cfg_text is not None:
                self.config_file = cfg_text.display
                read_config(cfg_text.display, cfg_text.lines, self.defines, self.diags, self.parsers.pp)
        elif opts.use_default_cfg:
            self.defines.no_config = True     # (a caller that turned the default off wants warnings only)
        if not opts.main.is_file():
            self.diags.report("E-FILE-NOT-FOUND", NO_SPAN, f"main program {opts.main} not found")
            return self._empty()
        src_files: list[ast.SourceFile] = []
        seen: set[Path] = set()
        def_requests: list[tuple[ast.DefineFile, str, Path]] = []
        self._load_sources(self.folders.resolved(opts.main), seen, src_files, def_requests)
        if src_files and is_module(src_files[0]):
            # one clear error, not an E-SYM-UNDEF per symbol the main program's definition files would give
            self.diags.report("E-MAIN-MODULE", Span(src_files[0].path, 1, 1), f"{opts.main.name} is a module (it exports labels with GLOBAL "
                              "and has no code before its first LBL): give the main program that USES it")
            return self._empty()

        global_defs: list[ast.DefFile] = []
        local_defs: dict[str, list[ast.DefFile]] = {}
        loaded: dict[Path, ast.DefFile] = {}
        for extra in opts.extra_global_defs:
            self._def_missing = False
            d = self._load_def(self.folders.resolved(extra), NO_SPAN, loaded, set())
            if self._def_missing:
                self.symbols_incomplete.add("*")
            global_defs.extend(d)
        # SYSTEM.DEF first when it is named, then in the order named.
        def_requests.sort(key=lambda r: 0 if Path(r[0].file).name.lower() == "system.def" else 1)
        for request, owner, base in def_requests:
            path = self.folders.find(request.file, request.span, self.diags, base)
            self._def_missing = path is None
            defs = self._load_def(path, request.span, loaded, set()) if path is not None else []
            if self._def_missing:
                self.symbols_incomplete.add("*" if request.is_global else owner)
            if request.is_global:
                global_defs.extend(d for d in defs if d not in global_defs)
            else:
                local_defs.setdefault(owner, []).extend(defs)
        number_mp4111 = self._number_mp4111()
        unused_overrides(self.defines, self.diags)
        masks = read_masks(opts.main, self.folders, self.diags, opts.encoding)
        return ParsedProject(tuple(src_files), tuple(global_defs), {k: tuple(v) for k, v in local_defs.items()},
                             dict(self.defines.values), tuple(self.inactive), tuple(self.files_read), self.line_count,
                             frozenset(self.symbols_incomplete), self.labels_incomplete, number_mp4111,
                             self.config_file, masks)

    def _number_mp4111(self) -> int | None:
        """DEFINE NUMBERMP4111 = n of the configuration (OEM.SYS's setting), checked against T96 ... T999."""
        self.defines.used.setdefault("numbermp4111", "NUMBERMP4111")     # (so `-D NUMBERMP4111=n` is not unused)
        key = next((k for k in self.defines.values if k.lower() == "numbermp4111"), None)
        if key is None:
            return None
        value = self.defines.values[key]
        if not isinstance(value, int) or not 0 <= value <= MAX_NUMBER_MP4111:
            self.diags.report("E-CFG-SYNTAX", self.defines.spans[key], f"NUMBERMP4111 = {value!r}: expected a number "
                              f"of additional timers 0 ... {MAX_NUMBER_MP4111}")
            return None
        return value

    def _empty(self) -> ParsedProject:
        return ParsedProject((), (), {}, dict(self.defines.values), (), tuple(self.files_read), self.line_count)

    def _load_sources(self, main: Path, seen: set[Path], out: list[ast.SourceFile],
                      def_requests: list[tuple[ast.DefineFile, str, Path]]) -> None:
        """Read the main file and, depth-first in USES order, every module it uses (each file once).

        An explicit stack of statement iterators instead of recursion: a USES chain may be longer than
        Python's recursion limit, and the order is exactly that of the recursive walk (a module's own
        #define and USES lines are taken when its USES line is reached)."""
        stack: list[tuple[Path, str, Iterator[ast.Statement]]] = []
        requests = (ast.DefineFile, ast.Uses)

        def enter(path: Path, at: Span) -> None:
            if path in seen:
                return
            seen.add(path)
            text = self._read(path, at)
            if text is None:
                self.labels_incomplete = True
                return
            parsed = self.parsers.src.parse_file(text.display, self._preprocess(text), len(text.lines), self.diags)
            out.append(parsed)
            # (only these two statements matter here: the walk below skips the rest of the file at once)
            wanted = [s for s in parsed.statements if type(s) in requests]
            stack.append((path, parsed.path, iter(wanted)))

        enter(main, NO_SPAN)
        while stack:
            path, display, statements = stack[-1]
            stmt = next(statements, None)
            if stmt is None:
                stack.pop()
            elif isinstance(stmt, ast.DefineFile):
                def_requests.append((stmt, display, path.parent))
            elif isinstance(stmt, ast.Uses):
                target = self.folders.find(stmt.file, stmt.span, self.diags, path.parent)
                if target is None:
                    self.labels_incomplete = True
                else:
                    enter(self.folders.resolved(target), stmt.span)

    def _load_def(self, path: Path, at: Span, loaded: dict[Path, ast.DefFile], active: set[Path]) -> list[ast.DefFile]:
        path = self.folders.resolved(path)
        if path in loaded:
            return [loaded[path]]
        if path in active:
            self.diags.report("E-FILE-INCLUDE-CYCLE", at, f"{path.name} includes itself")
            return []
        if len(active) >= MAX_DEF_NESTING:
            # (a chain of distinct files this deep is generated, not written; it would exhaust the stack)
            self.diags.report("E-FILE-INCLUDE-CYCLE", at, f"definition files nested more than {MAX_DEF_NESTING} deep")
            self._def_missing = True
            return []
        text = self._read(path, at)
        if text is None:
            self._def_missing = True
            return []
        active.add(path)
        lines = self._preprocess(text)
        parsed = self.parsers.defs.parse_file(text.display, lines, len(text.lines), self.diags)
        result: list[ast.DefFile] = []
        for inc in parsed.includes:
            target = self.folders.find(inc.file, inc.span, self.diags, path.parent)
            if target is None:
                self._def_missing = True
            else:
                result.extend(self._load_def(target, inc.span, loaded, active))
        loaded[path] = parsed
        result.append(parsed)
        active.discard(path)
        return result


def load_project(options: ProjectOptions, semantics: Semantics, diags: Diagnostics,
                 parsers: Parsers | None = None) -> ParsedProject:
    """Read and parse the project; `parsers` (made for the same semantics) lets runs share line caches."""
    return _Loader(options, semantics, diags, parsers).load()
