"""Output-directory lock (ftc_mc.io.lock): one writer per folder; a dead holder never blocks."""

import datetime as dt
import json
import os
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from ftc_mc.errors import UserError
from ftc_mc.io.lock import LOCK_NAME, acquire, holder

ROOT = Path(__file__).resolve().parents[1]

HOLDER_SNIPPET = textwrap.dedent("""
    import socket, sys, time
    from ftc_mc.io.lock import acquire
    if len(sys.argv) > 2:         # pretend to run on another host
        socket.gethostname = lambda: sys.argv[2]
    with acquire(sys.argv[1], command="ftc-mc run child.yaml"):
        print("locked", flush=True)
        sys.stdin.read()          # hold until the test closes our stdin
    print("released", flush=True)
""")


def _spawn_holder(directory, *extra):
    """A second process that takes the lock on ``directory`` and waits."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    child = subprocess.Popen([sys.executable, "-c", HOLDER_SNIPPET, str(directory), *extra],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env=env)
    line = child.stdout.readline()
    if line.strip() != "locked":
        child.kill()
        _, err = child.communicate(timeout=10)
        pytest.fail(f"holder process did not take the lock: {line!r} {err}")
    return child


def _stop(child, kill=False):
    if child.poll() is None:
        if kill:
            child.kill()
        else:
            child.stdin.close()
    try:
        child.wait(timeout=20)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def _dead_pid():
    """The pid of a process that has exited (and been reaped)."""
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    try:
        os.kill(p.pid, 0)
    except ProcessLookupError:
        return p.pid
    pytest.skip("pid of the exited process was reused immediately")


def _write_lock(directory, **fields):
    info = {"pid": os.getpid(), "hostname": socket.gethostname(),
            "started": dt.datetime.now(dt.timezone.utc).isoformat(),
            "command": "ftc-mc run other.yaml"}
    info.update(fields)
    (Path(directory) / LOCK_NAME).write_text(json.dumps(info))
    return info


def _lock_info(directory):
    return json.loads((Path(directory) / LOCK_NAME).read_text())


def test_second_process_is_refused_with_a_clear_message(tmp_path):
    out = tmp_path / "out"
    child = _spawn_holder(out)
    try:
        with pytest.raises(UserError) as err:
            with acquire(out):
                pytest.fail("took a lock held by a live process")
        msg = str(err.value)
        assert len(msg.splitlines()) == 1
        assert str(out) in msg
        assert f"pid {child.pid}" in msg
        assert "ftc-mc run child.yaml" in msg
        # the refused attempt left the owner's lock untouched
        assert _lock_info(out)["pid"] == child.pid
        assert holder(out)["pid"] == child.pid
    finally:
        _stop(child)
    assert child.stdout.read().strip() == "released"
    assert not (out / LOCK_NAME).exists()
    with acquire(out):  # free again after the owner released it
        assert _lock_info(out)["pid"] == os.getpid()


def test_lock_of_a_killed_process_is_taken_over(tmp_path):
    out = tmp_path / "out"
    child = _spawn_holder(out)
    _stop(child, kill=True)  # SIGKILL: no cleanup, the lock file stays behind
    assert _lock_info(out)["pid"] == child.pid
    assert holder(out) is None
    with acquire(out, command="me") as lk:
        info = _lock_info(out)
        assert info["pid"] == os.getpid() and info["command"] == "me"
        assert lk.held
    assert not (out / LOCK_NAME).exists()


def test_stale_lock_is_taken_over(tmp_path):
    pid = _dead_pid()
    _write_lock(tmp_path, pid=pid)
    with acquire(tmp_path):
        info = _lock_info(tmp_path)
        assert info["pid"] == os.getpid()
        assert info["hostname"] == socket.gethostname()
        dt.datetime.fromisoformat(info["started"])
        assert isinstance(info["command"], str)
    assert not (tmp_path / LOCK_NAME).exists()


@pytest.mark.parametrize("content", [
    b"", b"\n", b"not json", b"\xff\xfe\x00garbage", b"[1, 2]", b"{}", b"null",
    b'{"pid": "123", "hostname": "h", "started": "2026-01-01T00:00:00"}',
    b'{"pid": -5, "hostname": "h", "started": "2026-01-01T00:00:00"}',
    b'{"pid": true, "hostname": "h", "started": "2026-01-01T00:00:00"}',
    b'{"pid": 1, "hostname": 3, "started": "2026-01-01T00:00:00"}',
    b'{"pid": 1, "hostname": "h", "started": "yesterday"}',
    b'{"pid": 1, "hostname": "h"}',
    b'{"pid": 1, "hostname": "h", "started": "2026-01-01T00:00:00"',  # truncated
    b"[" * 100_000,
], ids=lambda c: repr(c[:20]))
def test_corrupt_lock_is_taken_over(tmp_path, content):
    (tmp_path / LOCK_NAME).write_bytes(content)
    t0 = time.monotonic()
    with acquire(tmp_path):
        assert _lock_info(tmp_path)["pid"] == os.getpid()
    assert time.monotonic() - t0 < 5
    assert not (tmp_path / LOCK_NAME).exists()


def test_lock_is_released_on_exception(tmp_path):
    with pytest.raises(RuntimeError, match="boom"):
        with acquire(tmp_path):
            assert (tmp_path / LOCK_NAME).exists()
            raise RuntimeError("boom")
    assert not (tmp_path / LOCK_NAME).exists()
    with pytest.raises(KeyboardInterrupt):
        with acquire(tmp_path):
            raise KeyboardInterrupt
    assert not (tmp_path / LOCK_NAME).exists()
    with acquire(tmp_path):  # and can be taken again
        pass


def test_lock_file_contents(tmp_path):
    before = dt.datetime.now(dt.timezone.utc)
    with acquire(tmp_path, command="ftc-mc scenario configs/paper_scenario.yaml"):
        info = _lock_info(tmp_path)
    assert info["pid"] == os.getpid()
    assert info["hostname"] == socket.gethostname()
    started = dt.datetime.fromisoformat(info["started"])
    assert started.tzinfo is not None
    assert before <= started <= dt.datetime.now(dt.timezone.utc)
    assert info["command"] == "ftc-mc scenario configs/paper_scenario.yaml"


def test_default_command_is_argv(tmp_path):
    with acquire(tmp_path):
        cmd = _lock_info(tmp_path)["command"]
    assert isinstance(cmd, str) and cmd


def test_nested_acquire_in_one_process_is_refused(tmp_path):
    with acquire(tmp_path):
        with pytest.raises(UserError, match=f"pid {os.getpid()}"):
            with acquire(tmp_path):
                pass
        assert _lock_info(tmp_path)["pid"] == os.getpid()  # outer lock intact
    assert not (tmp_path / LOCK_NAME).exists()







def test_created_directory_is_removed_if_left_empty(tmp_path):
    out = tmp_path / "a" / "b"
    with acquire(out):
        assert out.is_dir()
    assert not (tmp_path / "a").exists()  # parents created for it go too
    with pytest.raises(ValueError):
        with acquire(out):
            raise ValueError("campaign failed before writing")
    assert not (tmp_path / "a").exists()
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "other").write_text("x")
    with acquire(out):
        pass
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["other"]
    with acquire(out):
        (out / "summary.md").write_text("x")
    assert out.is_dir() and not (out / LOCK_NAME).exists()
    existing = tmp_path / "existing"
    existing.mkdir()
    with acquire(existing):
        pass
    assert existing.is_dir()


def test_refused_lock_leaves_no_directory(tmp_path):
    out = tmp_path / "out"
    (tmp_path / "file").write_text("")
    with pytest.raises(UserError, match="not a directory"):
        with acquire(tmp_path / "file"):
            pass
    child = _spawn_holder(out)
    try:
        with pytest.raises(UserError):
            with acquire(out):
                pass
    finally:
        _stop(child)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_holder_on_another_host_is_named(tmp_path):
    # a lock on a shared file system: the message names the holder's host
    child = _spawn_holder(tmp_path, "elsewhere.example")
    try:
        with pytest.raises(UserError, match="on host elsewhere.example") as err:
            with acquire(tmp_path):
                pass
        assert str(tmp_path) in str(err.value) and f"pid {child.pid}" in str(err.value)
        assert holder(tmp_path)["hostname"] == "elsewhere.example"
    finally:
        _stop(child)


def test_someone_elses_lock_is_not_removed(tmp_path):
    # our lock file is deleted by hand and another process locks a new one:
    # releasing ours must leave theirs in place
    child = None
    try:
        with acquire(tmp_path):
            (tmp_path / LOCK_NAME).unlink()
            child = _spawn_holder(tmp_path)
        assert _lock_info(tmp_path)["pid"] == child.pid
        assert holder(tmp_path)["pid"] == child.pid
    finally:
        if child is not None:
            _stop(child)
    assert holder(tmp_path) is None


def test_a_holder_probe_does_not_refuse_a_free_directory(tmp_path):
    # holder() takes a shared lock for an instant; acquire() waits that out
    (tmp_path / LOCK_NAME).write_text("{}")
    fd = os.open(tmp_path / LOCK_NAME, os.O_RDONLY)
    fcntl = pytest.importorskip("fcntl")
    fcntl.flock(fd, fcntl.LOCK_SH)
    timer = threading.Timer(0.05, os.close, [fd])
    timer.start()
    try:
        with acquire(tmp_path):
            assert _lock_info(tmp_path)["pid"] == os.getpid()
    finally:
        timer.join()


RACE_SNIPPET = textwrap.dedent("""
    import sys, time
    from ftc_mc.errors import UserError
    from ftc_mc.io.lock import acquire
    go = float(sys.argv[2])
    while time.time() < go:
        time.sleep(0.001)
    try:
        with acquire(sys.argv[1]):
            print("won", flush=True)
            time.sleep(1.5)
    except UserError:
        print("refused", flush=True)
""")


def test_racing_takeover_of_a_stale_lock_has_one_winner(tmp_path):
    _write_lock(tmp_path, pid=_dead_pid())
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    go = time.time() + 1.0
    procs = [subprocess.Popen([sys.executable, "-c", RACE_SNIPPET, str(tmp_path), str(go)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=env) for _ in range(6)]
    outs = []
    try:
        for p in procs:
            out, err = p.communicate(timeout=60)
            assert p.returncode == 0, err
            outs.append(out.strip())
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()
    assert sorted(outs) == ["refused"] * 5 + ["won"], outs
    assert not (tmp_path / LOCK_NAME).exists()
    assert [p.name for p in tmp_path.iterdir()] == []  # no temporary files left


def test_lock_path_that_is_a_folder_is_a_user_error(tmp_path):
    (tmp_path / LOCK_NAME).mkdir()
    with pytest.raises(UserError, match="cannot use the lock file"):
        with acquire(tmp_path):
            pass
