"""Submit jobs in the ST (transpiler/backends/st/jobs.py): the queue block against the interpreter's queue model
(transpiler/exec/interp/submit.py) command by command on the built-in executor, and the translation of SUBM,
RPLY and CAN (where a CAN may end the running job, and where it cannot be translated)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, ProgramInstance, Task, VarSection
from transpiler.backends.st import jobs
from transpiler.backends.st.writer import render_st
from transpiler.exec.interp.submit import SubmitQueue
from transpiler.exec.stexec import load_st
from tests.text_project import BACKENDS, cosim, translate

GLOBALS = [("G_CMD", "INT"), ("G_JOB", "INT"), ("G_ID", "DINT"), ("G_RESULT", "DINT"), ("G_QUEUE", jobs.QUEUE_TYPE)]


def _queue_runtime(model: str):
    # The queue is a global STRUCT the block gets in-out, as the translation passes it; a fresh block instance every
    # cycle shows that the block keeps no state of its own.
    ext = VarSection("VAR_EXTERNAL", tuple(IecVar(n, t) for n, t in GLOBALS))
    prog = Pou("HARNESS", "PROGRAM", (ext, VarSection("VAR", (IecVar("B1", jobs.QUEUE_FB), IecVar("B2", jobs.QUEUE_FB),
                                                              IecVar("FLIP", "BOOL")))),
               "FLIP := NOT FLIP;\nIF FLIP THEN\n    B1(CMD := G_CMD, JOB := G_JOB, ID := G_ID, Q := G_QUEUE);\n"
               "    G_RESULT := B1.RESULT;\nELSE\n    B2(CMD := G_CMD, JOB := G_JOB, ID := G_ID, Q := G_QUEUE);\n"
               "    G_RESULT := B2.RESULT;\nEND_IF;")
    config = Configuration("CONFIG0", "RES0", (Task("TASK0", 10),), (ProgramInstance("INST0", "TASK0", "HARNESS"),),
                           (VarSection("VAR_GLOBAL", tuple(IecVar(n, t) for n, t in GLOBALS)),))
    project = IecProject("HARNESS", tuple(jobs.queue_types(model)), (jobs.queue_fb(model), prog), config)
    return load_st(render_st(project), "queue.st").instantiate()


class _Model:
    """The interpreter's queue driven the way the machine drives it: cycles advance at the end of a job phase."""

    def __init__(self, model: str):
        self.queue = SubmitQueue(model)
        self.cycle = 0

    def run(self, cmd: int, job: int, ident: int) -> int | None:
        q = self.queue
        if cmd == jobs.SUBMIT:
            return q.submit(lambda _: None, 0, f"job{job}", self.cycle) if q.running is None else 0
        if cmd == jobs.REPLY:
            return q.reply(ident)
        if cmd == jobs.CANCEL:
            return int(q.cancel(ident))
        if cmd == jobs.TAKE:
            taken = q.take(self.cycle)
            if taken is not None:       # (the job runner ends a job before it takes the next)
                q.running = taken
            return int(taken.label[3:]) if taken is not None else 0
        if cmd == jobs.ENDED:
            q.running = None
        elif cmd == jobs.PHASE_END:
            self.cycle += 1
        return None


COMMANDS = st.lists(st.tuples(st.sampled_from([jobs.SUBMIT] * 4 + [jobs.REPLY, jobs.CANCEL, jobs.TAKE, jobs.ENDED,
                                                                   jobs.PHASE_END]),
                              st.integers(1, 3), st.integers(-1, 12)), max_size=60)


@pytest.mark.parametrize("model", ["same_cycle", "next_cycle"])
def test_queue_block_answers_every_command_as_the_interpreters_queue(model):
    # Catches: identifiers not skipping those in use or not wrapping 255 -> 1, a full queue accepting a ninth job,
    # SUBM accepted while a job runs, RPLY not telling running from waiting, CAN removing the wrong entry, FIFO
    # order broken, next_cycle running a job in the cycle that queued it.
    rt = _queue_runtime(model)

    @settings(max_examples=60, deadline=None)
    @given(COMMANDS)
    def check(commands):
        nonlocal rt
        rt = _queue_runtime(model)
        ref = _Model(model)
        for n, (cmd, job, ident) in enumerate(commands):
            rt.set("G_CMD", cmd)
            rt.set("G_JOB", job)
            rt.set("G_ID", ident)
            rt.run_cycle()
            expected = ref.run(cmd, job, ident)
            if expected is not None:
                assert rt.get("G_RESULT") == expected, (n, commands[:n + 1])

    check()


def test_identifiers_wrap_from_255_to_1_and_skip_queued_ones():
    rt = _queue_runtime("same_cycle")

    def command(cmd: int, job: int = 1, ident: int = 0) -> int:
        rt.set("G_CMD", cmd)
        rt.set("G_JOB", job)
        rt.set("G_ID", ident)
        rt.run_cycle()
        return rt.get("G_RESULT")

    assert command(jobs.SUBMIT) == 1             # stays queued throughout
    for expected in range(2, 256):
        assert command(jobs.SUBMIT, 2) == expected
        assert command(jobs.CANCEL, ident=expected) == 0      # removed again (it was not running)
    assert command(jobs.SUBMIT, 2) == 2          # after 255 comes 1, which the first job still holds
    assert command(jobs.REPLY, ident=1) == 2
    assert command(jobs.TAKE) == 1               # oldest first


def _translate(tmp_path, source: str):
    from transpiler import api
    main = tmp_path / "main.src"
    main.write_text(source, encoding="utf-8")
    return api.transpile(api.load_project(api.project_options(main)), formats=("st",), allow_untranslated=True)


def test_can_in_the_job_subprogram_ends_it_and_in_a_callee_of_a_job_is_not_translated(tmp_path):
    source = ("L M4172\nSUBM Job\n= W0\nCAN W0\nEM\n"
              "LBL Job\nL I1\nJPF Go\nCAN W0\nLBL Go\nCM Helper\nL K1\n= W2\nEM\n"
              "LBL Helper\nCAN W0\nEM\n")
    result = _translate(tmp_path, source)
    st_text = result.st_text
    job = st_text[st_text.index("FUNCTION_BLOCK Job"):]
    job = job[:job.index("END_FUNCTION_BLOCK")]
    assert "RETURN; (* the running job cancelled itself *)" in job
    main = st_text[st_text.index("PROGRAM main"):]
    main = main[:main.index("END_PROGRAM")]
    assert "HH_Jobs(CMD := 3" in main and "RETURN" not in main      # the main program is never a running job
    assert [d.span.line for d in result.diagnostics if d.code == "E-UNSUPPORTED"] == [16]


def test_jobs_run_in_a_second_program_after_the_main_one_with_their_own_registers(tmp_path):
    source = "L M4172\nSUBM Job\n= W0\nL K5\n= X\nEM\nLBL Job\nL X\n= W2\nEM\n"
    st_text = _translate(tmp_path, source).st_text
    resource = st_text[st_text.index("RESOURCE"):]
    assert resource.index("PROGRAM PLC_main") < resource.index("PROGRAM PLC_HH_SubmitJobs")
    runner = st_text[st_text.index("PROGRAM HH_SubmitJobs"):]
    runner = runner[:runner.index("END_PROGRAM")]
    # X is saved, cleared for the job and restored around the job's call
    save, clear, call, restore = (runner.index(t) for t in (":= HH_X;", "HH_X := 0;", "Job_1();", "HH_X := main_"))
    assert save < clear < call < restore


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_job_command_saves_no_accumulator_value_it_replaces(tmp_path, backend):
    # RPLY's result is still in flight in WA when SUBM replaces it: nothing reads it, so it is not saved to HH_WA;
    # the same value pushed to the data stack first is saved (the stack reads it) and comes back by PLW.
    source = ("L M4172\nJPF Go\nSUBM Job\n= W0\nLBL Go\n"
              "RPLY W0\nSUBM Job\n= W2\n"
              "RPLY W0\nPSW\nSUBM Job\n= W4\nPLW\n= W6\nEM\n"
              "LBL Job\nL K1\n= W8\nEM\n")
    project = translate(tmp_path, source, "cycles: 3\nexpect:\n  - cycle: 0\n    values: {W6: 2}\n")
    main = project.out.st_text[project.out.st_text.index("PROGRAM main"):]
    main = main[:main.index("END_PROGRAM")]
    assert main.count("HH_Jobs(CMD := 2") == 2
    assert "HH_WA := HH_Jobs.RESULT" not in main
    result = cosim(project, backend=backend)
    assert result.equivalent, result
    assert not result.expectation_failures
