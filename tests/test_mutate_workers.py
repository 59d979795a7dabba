"""Mutants judged in forked processes (verify/mutate._each): compiled code of a mutant can crash the process running
it (a segmentation fault in the C of a matiec build); that mutant gets an error verdict, a new process takes the
rest, and nothing waits for a result that cannot come."""

from __future__ import annotations

import os
import signal

import pytest

from transpiler.verify.mutate import _each, _exit


def _square_or_die(item: int) -> int:
    if item == 3:
        os.kill(os.getpid(), signal.SIGSEGV)
    if item == 5:
        os._exit(7)
    return item * item


@pytest.mark.parametrize("jobs", [1, 2, 3])
def test_an_item_whose_process_dies_gets_the_crash_verdict_and_the_others_still_run(jobs):
    results = dict(_each(_square_or_die, range(8), jobs, crashed=lambda item, code: ("crashed", code)))
    assert sorted(results) == list(range(8))
    assert results[3] == ("crashed", -signal.SIGSEGV) and results[5] == ("crashed", 7)
    assert all(results[i] == i * i for i in (0, 1, 2, 4, 6, 7))


def test_without_a_crash_verdict_a_dying_worker_is_an_error_not_a_hang():
    with pytest.raises(RuntimeError, match="exit code"):
        dict(_each(_square_or_die, range(8), 2))


def test_in_process_without_jobs_and_exit_words():
    assert dict(_each(lambda i: i + 1, range(3), 1)) == {0: 1, 1: 2, 2: 3}
    assert _exit(-11) == "signal 11, SIGSEGV" and _exit(3) == "exit code 3"
