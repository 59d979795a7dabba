"""The CONFIGURATION: its globals, the one RESOURCE, its TASKs and program instances."""

from __future__ import annotations

from typing import Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.codegen import PouCompiler
from transpiler.exec.stexec.compiler_base import CompilerBase
from transpiler.exec.stexec.model import ProgramInstance, TaskInfo


class ConfigDeclarer(CompilerBase):
    """The CONFIGURATION: its globals, the one RESOURCE, its TASKs and program instances."""

    def declare_configuration(self, cfg: n.Configuration, ordinal: int) -> None:
        self.has_configuration = True
        for block in cfg.globals:
            self.declare_globals(block, ordinal)
        if len(cfg.resources) > 1:
            self.error(cfg.resources[1].span, "use exactly one RESOURCE (matiec defines the POUs once per "
                                              "resource and the link fails)")
        for res in cfg.resources[:1]:
            for block in res.globals:
                self.declare_globals(block, ordinal)
            tasks: dict[str, TaskInfo] = {}
            for task in res.tasks:
                info = self.declare_task(task, ordinal)
                if info is not None:
                    if info.name.lower() in tasks:
                        self.error(task.span, f"task '{task.name}' is declared twice")
                    tasks[info.name.lower()] = info
                    self.tasks.append(info)
            if not tasks:
                self.error(res.span, "the resource needs at least one periodic TASK (matiec: you must define at "
                                     "least one periodic task)")
            names = set()
            for pc in res.programs:
                self.declare_program_instance(pc, tasks, names, ordinal)

    def declare_task(self, task: n.Task, ordinal: int) -> Optional[TaskInfo]:
        params = {name.lower(): (expr, span) for name, expr, span in task.params}
        unknown = set(params) - {"interval", "priority", "single"}
        if unknown:
            self.error(task.span, f"unknown TASK parameter {', '.join(sorted(unknown))}")
            return None
        if "single" in params:
            self.error(task.span, "TASK SINGLE is not supported by the built-in executor")
            return None
        if "priority" not in params:
            self.error(task.span, "no task initialization defined in task declaration (PRIORITY is required)")
            return None
        if "interval" not in params:
            self.error(task.span, "the built-in executor needs a periodic TASK with INTERVAL")
            return None
        pc = PouCompiler(self.ctx, None, ordinal)
        iv = pc.expr(params["interval"][0])
        pr = pc.expr(params["priority"][0])
        if iv.ty is T.ERR or pr.ty is T.ERR:
            return None
        if T.base(iv.ty) is not T.TIME or iv.const is None or iv.const <= 0:
            self.error(params["interval"][1], "TASK INTERVAL must be a positive TIME literal such as T#10ms")
            return None
        if not isinstance(pr.const, int) or isinstance(pr.const, bool):
            self.error(params["priority"][1], "TASK PRIORITY must be an integer literal")
            return None
        return TaskInfo(task.name, iv.const, pr.const, task.span)

    def declare_program_instance(self, pc: n.ProgramConf, tasks: dict[str, TaskInfo], names: set[str],
                                 ordinal: int) -> None:
        pou = self.ctx.pous.get(pc.type_name.lower())
        if pou is None or pou.kind != "program":
            self.error(pc.span, f"'{pc.type_name}' is not a PROGRAM declared before the configuration")
            return
        if pc.name.lower() == pou.key:
            self.error(pc.span, "invalid program name defined in program configuration (the instance name equals "
                                "the program type name)")
            return
        if pc.name.lower() in names or pc.name.lower() in self.ctx.globals:
            self.error(pc.span, f"'{pc.name}' is declared twice")
            return
        if pc.has_args:
            self.error(pc.span, "program parameters bound in the configuration make matiec generate C that does "
                                "not compile; share data through VAR_GLOBAL/VAR_EXTERNAL")
            return
        task = None
        if pc.task is not None:
            task = tasks.get(pc.task.lower())
            if task is None:
                self.error(pc.span, f"unknown task '{pc.task}'")
                return
        names.add(pc.name.lower())
        self.programs.append(ProgramInstance(pc.name, pou, task, pc.span))
