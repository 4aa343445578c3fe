"""A server's spool of request bodies: removed when the server stops, and by the next server started on
the same directory when it was killed; never while its server runs. Real processes and real locks."""

import os
import signal
import subprocess
import sys
import textwrap

from bootmap.service.spool import PREFIX, Spool, sweep

HOLD = textwrap.dedent("""
    import sys, time
    from bootmap.service.spool import Spool
    spool = Spool.open(sys.argv[1])
    fd, path = spool.new_file()
    print(spool.directory, flush=True)
    time.sleep(60)
""")


def _holder(parent):
    """A process that opens a spool under ``parent``, writes one file to it and waits: (process, spool)."""
    p = subprocess.Popen([sys.executable, "-c", HOLD, str(parent)], stdout=subprocess.PIPE, text=True)
    return p, p.stdout.readline().strip()


def test_a_killed_servers_spool_is_swept_by_the_next_and_a_running_ones_is_kept(tmp_path):
    dead, dead_dir = _holder(tmp_path)
    live, live_dir = _holder(tmp_path)
    try:
        assert os.listdir(dead_dir) and os.listdir(live_dir)  # its lock and one body each
        os.kill(dead.pid, signal.SIGKILL)
        dead.wait(10)
        mine = Spool.open(tmp_path)  # sweeps first
        try:
            assert not os.path.exists(dead_dir)
            assert os.path.isdir(live_dir) and len(os.listdir(live_dir)) == 2
            assert sweep(tmp_path) == []  # this one's and the live one's are held
            assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
                [os.path.basename(live_dir), mine.directory.name])
        finally:
            mine.close()
        assert not mine.directory.exists()
    finally:
        live.kill()
        live.wait(10)


def test_the_sweep_leaves_what_it_did_not_make(tmp_path):
    """A directory of the spool's name with no lock in it, a file of that name, a hidden half-made spool."""
    (tmp_path / (PREFIX + "stranger")).mkdir()
    (tmp_path / (PREFIX + "stranger") / "keep").write_text("x")
    (tmp_path / (PREFIX + "file")).write_text("x")
    (tmp_path / ("." + PREFIX + "partial")).mkdir()
    (tmp_path / ("." + PREFIX + "partial") / "lock").write_text("")
    before = sorted(p.name for p in tmp_path.iterdir())
    assert sweep(tmp_path) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == before
