"""Front-end driver: configuration, preprocessing and parsing of every project file in the spec's order (1.3)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Mapping

from . import ast
from .diagnostics import Diagnostics, Span, NO_SPAN
from .parse import DefParser, SrcParser
from .preprocess import (DefineValue, Defines, InactiveRegion, PPParser, Preprocessor, find_default_cfg,
                         initial_defines, read_config)
from .semantics import Semantics
from .sources import ProjectFolders, SourceText, read_source


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


@dataclasses.dataclass
class ProjectOptions:
    main: Path
    cfg: Path | None = None
    use_default_cfg: bool = True
    defines: Mapping[str, DefineValue] = dataclasses.field(default_factory=dict)
    include_dirs: tuple[Path, ...] = ()
    extra_global_defs: tuple[Path, ...] = ()


class _Loader:
    def __init__(self, options: ProjectOptions, semantics: Semantics, diags: Diagnostics):
        self.options = options
        self.semantics = semantics
        self.diags = diags
        self.folders = ProjectFolders(options.main.parent, list(options.include_dirs))
        self.defines: Defines = initial_defines(options.defines)
        self.pp_parser = PPParser()
        self.src_parser = SrcParser()
        self.def_parser = DefParser()
        self.inactive: list[InactiveRegion] = []
        self.files_read: list[str] = []
        self.line_count = 0

    def _read(self, path: Path, at: Span) -> SourceText | None:
        text = read_source(path, self.folders, at, self.diags)
        if text is not None:
            self.files_read.append(text.display)
            self.line_count += len(text.lines)
        return text

    def _preprocess(self, text: SourceText) -> list:
        pre = Preprocessor(self.defines, self.diags, self.pp_parser)

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
            cfg_text = read_source(cfg, ProjectFolders(cfg.parent, []), NO_SPAN, self.diags)
            if cfg_text is not None:
                self.files_read.append(self.folders.display(cfg))
                read_config(cfg_text.display if cfg.parent.resolve() != self.folders.main_dir
                            else cfg_text.display, cfg_text.lines, self.defines, self.diags, self.pp_parser)
        if not opts.main.is_file():
            self.diags.error("E-FILE-NOT-FOUND", NO_SPAN, f"main program {opts.main} not found")
            return self._empty()
        src_files: list[ast.SourceFile] = []
        seen: set[Path] = set()
        def_requests: list[tuple[ast.DefineFile, str, Path]] = []
        self._load_src(opts.main.resolve(), NO_SPAN, seen, src_files, def_requests)

        global_defs: list[ast.DefFile] = []
        local_defs: dict[str, list[ast.DefFile]] = {}
        loaded: dict[Path, ast.DefFile] = {}
        for extra in opts.extra_global_defs:
            d = self._load_def(extra.resolve(), NO_SPAN, loaded, set())
            global_defs.extend(d)
        # SYSTEM.DEF first when it is named (spec 1.3 step 3), then in the order named.
        def_requests.sort(key=lambda r: 0 if Path(r[0].file).name.lower() == "system.def" else 1)
        for request, owner, base in def_requests:
            path = self.folders.find(request.file, request.span, self.diags, base)
            if path is None:
                continue
            defs = self._load_def(path, request.span, loaded, set())
            if request.is_global:
                global_defs.extend(d for d in defs if d not in global_defs)
            else:
                local_defs.setdefault(owner, []).extend(defs)
        return ParsedProject(tuple(src_files), tuple(global_defs), {k: tuple(v) for k, v in local_defs.items()},
                             dict(self.defines.values), tuple(self.inactive), tuple(self.files_read), self.line_count)

    def _empty(self) -> ParsedProject:
        return ParsedProject((), (), {}, dict(self.defines.values), (), tuple(self.files_read), self.line_count)

    def _load_src(self, path: Path, at: Span, seen: set[Path], out: list[ast.SourceFile],
                  def_requests: list[tuple[ast.DefineFile, str, Path]]) -> None:
        if path in seen:
            return
        seen.add(path)
        text = self._read(path, at)
        if text is None:
            return
        lines = self._preprocess(text)
        parsed = self.src_parser.parse_file(text.display, lines, len(text.lines), self.diags)
        out.append(parsed)
        for stmt in parsed.statements:
            if isinstance(stmt, ast.DefineFile):
                def_requests.append((stmt, parsed.path, path.parent))
            elif isinstance(stmt, ast.Uses):
                target = self.folders.find(stmt.file, stmt.span, self.diags, path.parent)
                if target is not None:
                    self._load_src(target.resolve(), stmt.span, seen, out, def_requests)

    def _load_def(self, path: Path, at: Span, loaded: dict[Path, ast.DefFile], active: set[Path]) -> list[ast.DefFile]:
        path = path.resolve()
        if path in loaded:
            return [loaded[path]]
        if path in active:
            self.diags.error("E-FILE-INCLUDE-CYCLE", at, f"{path.name} includes itself")
            return []
        text = self._read(path, at)
        if text is None:
            return []
        active.add(path)
        lines = self._preprocess(text)
        parsed = self.def_parser.parse_file(text.display, lines, len(text.lines), self.diags)
        result: list[ast.DefFile] = []
        for inc in parsed.includes:
            target = self.folders.find(inc.file, inc.span, self.diags, path.parent)
            if target is not None:
                result.extend(self._load_def(target, inc.span, loaded, active))
        loaded[path] = parsed
        result.append(parsed)
        active.discard(path)
        return result


def load_project(options: ProjectOptions, semantics: Semantics, diags: Diagnostics) -> ParsedProject:
    return _Loader(options, semantics, diags).load()
