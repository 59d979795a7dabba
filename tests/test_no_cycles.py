"""A compile and a translation leave no reference cycles behind: their data is freed when the result is dropped.

The pipeline pauses the cyclic collector (frontend/pipeline.py); a cycle anywhere in a run's objects (a bound
method kept by its own object, a closure that calls itself) would keep everything it reaches alive until the
collector runs, which for a large project is at process exit and costs a tenth of a second or more there."""

from __future__ import annotations

import gc
from pathlib import Path

import jinja2

from transpiler.backends.transpile import transpile_program
from transpiler.diagnostics import Diagnostics
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "basic_program" / "Main_PGM.src"


def _compile_and_translate() -> None:
    result = compile_project(ProjectOptions(main=SAMPLE), make_semantics("itnc530", {}))
    assert result.ok
    transpile_program(result.program, Diagnostics(), {}, {"st", "xml"})


def _cyclic_garbage_of(run) -> list[str]:
    """The classes (of this package) of the objects that only reference cycles kept alive after `run()`."""
    was_enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    gc.set_debug(gc.DEBUG_SAVEALL)
    try:
        run()
        gc.collect()
        # (the template engine's own objects form cycles when a template is loaded, the cache of compiled templates
        # with them; they hold no data of the run)
        return sorted({f"{type(o).__module__}.{type(o).__qualname__}" for o in gc.garbage
                       if type(o).__module__.startswith("transpiler") and not isinstance(o, jinja2.BytecodeCache)})
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        if was_enabled:
            gc.enable()


def test_a_compile_and_a_translation_leave_no_cycles():
    assert _cyclic_garbage_of(_compile_and_translate) == []


def test_the_check_sees_a_cycle():
    """The measurement itself: an object of this package kept by a cycle is found."""
    def leave_a_cycle():
        diags = Diagnostics()
        diags.me = diags

    assert _cyclic_garbage_of(leave_a_cycle) == ["transpiler.diagnostics.Diagnostics"]
