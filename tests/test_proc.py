"""Helper processes forked from a forkserver that preloaded their modules, and how they tell that the
process that started them is gone; independent work shared among processes."""

import multiprocessing
import os
import subprocess
import sys
import time

import pytest

from bootmap.proc import in_processes, parent_gone, preloaded_context


def _modules_and_parent(_):
    return "bootmap.tableau" in sys.modules, os.getppid()


def test_helpers_start_with_the_preloaded_modules_from_a_forkserver():
    # In a process of its own: the forkserver is one per process and reads its preload list once.
    code = ("import os\n"
            "from bootmap.proc import preloaded_context\n"
            "import test_proc\n"
            "ctx = preloaded_context(['bootmap.tableau'])\n"
            "with ctx.Pool(1) as pool:\n"
            "    loaded, parent = pool.apply(test_proc._modules_and_parent, (0,))\n"
            "print(ctx.get_start_method(), loaded, parent != os.getpid())\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                         cwd=os.path.dirname(__file__))
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["forkserver", "True", "True"]  # imported before the fork, by the forkserver


def test_the_owner_is_gone_when_the_parent_changed_or_the_owner_no_longer_runs():
    me, parent = os.getpid(), os.getppid()
    assert not parent_gone(parent, parent)  # spawned by its owner, who is there
    # Forked by a forkserver (here: this process's parent), owned by another process (here: this one).
    assert not parent_gone(me, parent)  # the owner runs
    assert parent_gone(parent, first_parent=me)  # the parent is no longer the one it started with...
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    assert parent_gone(dead.pid, parent)  # ...or the owner no longer runs
    assert preloaded_context(["bootmap.tableau"]).get_start_method() in multiprocessing.get_all_start_methods()


def test_nothing_raised_in_a_forked_child_before_its_work_escapes_into_the_parents_code(monkeypatch, tmp_path):
    # A Ctrl-C (or anything) raised in the child between the fork and the work would otherwise unwind into
    # the caller's frames in the child: a second copy of the caller (a sweep's worker loop) going on.
    import bootmap.proc as proc

    def interrupted(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(proc, "_die_with_parent", interrupted)
    me, escaped = os.getpid(), tmp_path / "escaped"
    try:
        outcome = proc.in_child(lambda: "done", 30)
    except BaseException:
        if os.getpid() != me:  # the child came back here: say so, and leave
            escaped.write_text("the child unwound into the caller")
            os._exit(0)
        raise
    assert not escaped.exists()
    assert outcome[0] == "failed" and "died without a result" in outcome[1]


def test_a_ctrl_c_in_the_child_during_its_work_is_the_works_outcome():
    import signal as sig

    from bootmap.proc import in_child

    # (as in a terminal: Python's own Ctrl-C handler, which a test worker of pytest-xdist replaces)
    previous = sig.signal(sig.SIGINT, sig.default_int_handler)
    try:
        outcome = in_child(lambda: os.kill(os.getpid(), sig.SIGINT) or time.sleep(5), 30)
    finally:
        sig.signal(sig.SIGINT, previous)
    assert outcome[0] == "failed" and outcome[1].startswith("KeyboardInterrupt")


def _scaled(factor, items, offsets=None):
    return [factor * x + (0 if offsets is None else o) for x, o in zip(items, offsets or [None] * len(items))]


@pytest.mark.parametrize("jobs", [1, 2])
@pytest.mark.parametrize("n", [0, 1, 7, 20])
def test_work_in_processes_gives_each_items_value_in_order(jobs, n):
    items, offsets = list(range(n)), [10 * k for k in range(n)]
    # One value per item, in the items' order, as the work done here gives them.
    assert in_processes(_scaled, jobs, (3,), items) == _scaled(3, items)
    assert in_processes(_scaled, jobs, (3,), items, offsets) == _scaled(3, items, offsets)
    assert in_processes(_scaled, jobs, (3,), items, None) == _scaled(3, items)
