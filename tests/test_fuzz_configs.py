"""Hostile and malformed configs for ``ftc-mc run``, ``sweep`` and ``scenario``.

Starting from what the shipped configs/elevon_lock.yaml and
configs/paper_scenario.yaml resolve to (every field listed), hypothesis mutates the
parsed YAML (wrong types, missing and unknown keys, NaN and inf, huge and negative
numbers, sections replaced by lists or scalars, anchors and alias bombs, Python tags)
and the raw bytes (non-UTF-8, truncation, stray YAML syntax). Every case that is not a
valid config must be refused the way the CLI promises: exit code 2, exactly one line
on stderr naming the field or the file problem, no traceback, and nothing created or
changed on disk (neither in --out nor under results/ in the working directory). A
mutated config that happens to be valid is never run (no real campaign starts here).

The generators include huge and tiny magnitudes (up to 1e308, subnormals) and
explicitly tagged scalars that PyYAML cannot construct (``!!int abc``...), which
found six bugs now covered by the ``test_regression_*`` tests at the end.  Runs
are derandomized (fixed examples); ``FTC_MC_FUZZ_RANDOM=1`` draws new ones.  Deep
nesting is exercised by ``test_regression_deep_nesting``.
"""

from __future__ import annotations

import copy
import hashlib
import math
import os
import tempfile
import time
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner
from hypothesis import HealthCheck, currently_in_test_context, event, given, settings
from hypothesis import strategies as st

from ftc_mc.cli import cli
from ftc_mc.config import Config, ScenarioConfig, load_any, parse_config
from ftc_mc.errors import UserError

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = {"run": ROOT / "configs" / "elevon_lock.yaml",
           "scenario": ROOT / "configs" / "paper_scenario.yaml",
           "sweep": ROOT / "configs" / "sweep.yaml"}
EXTRA_ARGS = {"sweep": ["--thresholds", "10"]}
"""Options a command needs besides its config."""
BASES = {cmd: load_any(p).model_dump(mode="json") for cmd, p in SHIPPED.items()}
"""What the shipped configs resolve to, every field listed: the mutations' start."""
SECTIONS = {"run": set(Config.model_fields), "scenario": set(ScenarioConfig.model_fields),
            "sweep": set(Config.model_fields)}
FULL = True  # every generator, including the inputs that once hit bugs
RANDOM = os.environ.get("FTC_MC_FUZZ_RANDOM") == "1"

MAX_SECONDS = 30.0  # "refused quickly": generous, so a loaded CI machine does not flake
"""A refused config must be refused this fast (imports are warmed up first)."""
MAX_LINE = 2000
"""Longest acceptable error line (an alias bomb must not be echoed back)."""

FILE_PROBLEMS = ("no such file", "not a regular file", "not UTF-8 text", "malformed YAML",
                 "the file is empty", "expected a mapping of sections", "cannot read")

FUZZ = settings(max_examples=100, deadline=None, derandomize=not RANDOM,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow, HealthCheck.filter_too_much,
                                       HealthCheck.data_too_large])


# -- helpers ----------------------------------------------------------------------

def _paths(node, prefix=()):
    """Every path (tuple of keys / indices) into the parsed base config."""
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out.append(prefix + (k,))
            out += _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out.append(prefix + (i,))
            out += _paths(v, prefix + (i,))
    return out


def _lookup(data, path):
    node = data
    for p in path:
        node = node[p]
    return node


PATHS = {cmd: _paths(data) for cmd, data in BASES.items()}
CONTAINERS = {cmd: [()] + [p for p in PATHS[cmd] if isinstance(_lookup(BASES[cmd], p), dict)]
              for cmd in BASES}


def _parent(data, path):
    """The container holding ``path``, or None if the path no longer exists."""
    try:
        node = _lookup(data, path[:-1])
    except (KeyError, IndexError, TypeError):
        return None
    if (isinstance(node, dict) and path[-1] in node) or (
            isinstance(node, list) and isinstance(path[-1], int) and path[-1] < len(node)):
        return node
    return None


def _snapshot(root: Path) -> dict:
    """Every file and folder under ``root`` with its content hash and mtime."""
    snap = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for d in dirnames:
            p = Path(dirpath, d)
            snap[str(p.relative_to(root))] = ("dir",)
        for f in filenames:
            p = Path(dirpath, f)
            st_ = p.lstat()
            digest = hashlib.sha1(p.read_bytes()).hexdigest() if p.is_file() else None
            snap[str(p.relative_to(root))] = ("file", st_.st_size, st_.st_mtime_ns, digest)
    return snap


def _oracle(cmd: str, raw: bytes):
    """(valid, data): whether the bytes are a valid config, and the parsed YAML."""
    try:
        data = yaml.safe_load(raw.decode("utf-8"))
    except Exception:  # noqa: BLE001 -- anything unreadable is invalid
        return False, None
    if not isinstance(data, dict):
        return False, data
    try:
        if cmd in ("run", "sweep"):
            parse_config(data)
        else:
            ScenarioConfig.model_validate(data)
    except Exception:  # noqa: BLE001 -- UserError, ValidationError, and known bugs
        return False, data
    return True, data


_WARM = set()


def _invoke(cmd, config_path, out_mode, monkeypatch, workdir: Path):
    """Run the CLI from ``workdir``; return (result, seconds, snapshots before/after)."""
    if cmd not in _WARM:  # import the command's modules before timing anything
        empty = workdir / ".warm.yaml"
        empty.write_text("")
        monkeypatch.chdir(workdir)
        CliRunner().invoke(cli, [cmd, str(empty), *EXTRA_ARGS.get(cmd, []), "--out",
                                 str(workdir / "warm-out")])
        empty.unlink()
        _WARM.add(cmd)
    args = [cmd, str(config_path), *EXTRA_ARGS.get(cmd, [])]
    if out_mode == "new":
        args += ["--out", str(workdir / "out" / "new")]
    elif out_mode == "existing":
        (workdir / "out").mkdir(exist_ok=True)
        (workdir / "out" / "notes.txt").write_text("keep me\n")
        args += ["--out", str(workdir / "out")]
    before = _snapshot(workdir)
    monkeypatch.chdir(workdir)
    t0 = time.perf_counter()
    res = CliRunner().invoke(cli, args)
    elapsed = time.perf_counter() - t0
    after = _snapshot(workdir)
    return res, elapsed, before, after


def _assert_refused(cmd, config_path, data, res, elapsed, before, after, workdir):
    """The CLI's promise for a bad config, with a readable failure message."""
    out = res.output
    where = f"\n  config {config_path}\n  output {out[:600]!r}"
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        import traceback
        tb = "".join(traceback.format_exception(*res.exc_info))
        raise AssertionError(f"uncaught {type(res.exception).__name__}{where}\n{tb}")
    assert res.exit_code == 2, f"exit code {res.exit_code}{where}"
    assert "Traceback" not in out, where
    lines = out.splitlines()
    assert len(lines) == 1, f"{len(lines)} lines of output{where}"
    assert res.stdout == "", f"error not on stderr{where}"
    line = lines[0]
    assert len(line) <= MAX_LINE, f"error line of {len(line)} characters{where}"
    prefix = f"ftc-mc: error: {config_path}: "
    assert line.startswith(prefix), f"line does not name the file{where}"
    rest = line[len(prefix):]
    if not any(rest.startswith(p) for p in FILE_PROBLEMS):
        keys = {str(k) for k in data} if isinstance(data, dict) else set()
        # the line starts with a field path: a top-level key (which may itself
        # contain dots or ": ", e.g. "x.y" or "a: b"), then ".sub" or ": problem"
        named = [k for k in keys | SECTIONS[cmd]
                 if rest.startswith(k + ": ") or rest.startswith(k + ".")]
        assert named, f"no field named{where}"
        assert any(rest.split(": ", 1)[1].strip() for _ in named), f"no problem stated{where}"
    assert elapsed < MAX_SECONDS, f"took {elapsed:.1f} s{where}"
    assert after == before, (f"files changed: {set(after) ^ set(before) or 'contents'}"
                             f"{where}")
    assert not (workdir / "results").exists()


def _check_case(cmd, raw: bytes, out_mode, monkeypatch, name="config.yaml"):
    """Write ``raw`` as a config, and check the CLI refuses it (unless valid)."""
    valid, data = _oracle(cmd, raw)
    if currently_in_test_context():
        event("valid (not run)" if valid else "refused")
    if valid:
        return "valid"  # never run a real campaign here
    with tempfile.TemporaryDirectory() as d:
        workdir = Path(d).resolve()
        cfg_dir = workdir / "in"
        cfg_dir.mkdir()
        path = cfg_dir / name
        path.write_bytes(raw)
        res, elapsed, before, after = _invoke(cmd, path, out_mode, monkeypatch, workdir)
        _assert_refused(cmd, path, data, res, elapsed, before, after, workdir)
    return "refused"


# -- strategies -------------------------------------------------------------------

LIMIT = 1e308 if FULL else 1e100
TINY = 0.0 if FULL else 1e-100

finite = st.floats(min_value=-LIMIT, max_value=LIMIT, allow_nan=False,
                   allow_infinity=False, allow_subnormal=FULL).filter(
                       lambda x: x == 0 or abs(x) >= TINY)
special_floats = st.sampled_from([math.nan, math.inf, -math.inf, -0.0, 0.0, -1.0, 1e100,
                                  -1e100, 1e-100, 0.05, 0.1, 0.3, 0.7, 1.0 - 1e-16, 1.0,
                                  20.0, 20.05, 1e6, 1e7]
                                 + ([1e308, 5e-324, 1.7976931348623157e308] if FULL else []))
big_ints = st.sampled_from([0, -1, 1, 2 ** 31, 2 ** 63 - 1, 2 ** 63, 2 ** 64, -2 ** 63,
                            10 ** 20, -10 ** 20, 10 ** 99, 4096, 4097, 100_000, 100_001,
                            10_000_000, 10_000_001] + ([10 ** 300, 10 ** 400] if FULL else []))
ints = st.integers(min_value=-10 ** 30, max_value=10 ** 30) | big_ints
texts = st.text(max_size=30) | st.sampled_from([
    "", " ", "nan", "NaN", "inf", "-inf", "Infinity", "1e400", "-1e400", "1e-3", "0x10",
    "1_000", "yes", "no", "on", "off", "null", "~", "true", "elevon_lock", "engine_loss",
    "trim", "both", "paper", "swapped", "reconfiguring", "nominal", "lock", "loss",
    "left_elevon", "20", "20.0", "-3", "\u202e", "\x85", "é", "🛩"])
keys = st.sampled_from(["bogus", "Trials", "seed ", " seed", "__class__", "__init__",
                        "model_config", "transitions", "campaign", "model", "x.y", "a: b",
                        "<<", "0", "null", "~", "?", "-", "#"]) | st.from_regex(
                            r"[A-Za-z_][A-Za-z0-9_]{0,15}", fullmatch=True)
scalars = (st.none() | st.booleans() | finite | special_floats | ints | texts
           | st.dates() | st.binary(max_size=8))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=4)
                      | st.dictionaries(keys | st.integers(-3, 3), inner, max_size=3),
                      max_leaves=8)

TAG_PLACEHOLDER = "FTCMCTAGPLACEHOLDER"
PYTHON_TAGS = [
    "!!python/object/apply:os.system ['touch PWNED_apply']",
    "!!python/object/new:os.system ['touch PWNED_new']",
    "!!python/object/apply:subprocess.check_output [['touch', 'PWNED_subprocess']]",
    "!!python/name:os.system",
    "!!python/module:os",
    "!!python/object:ftc_mc.config.schema.Config {}",
    "!!python/tuple [1, 2]",
    "!!python/unicode 'x'",
    "!<tag:yaml.org,2002:python/object/apply:os.system> ['touch PWNED_verbatim']",
    "!!python/object/apply:builtins.exec ['open(\"PWNED_exec\", \"w\").close()']",
]
OTHER_TAGS = ["!custom 3", "!<tag:example.com,2000:app/foo> bar", "!!map [1]", "!!set [1]",
              "!!str [1]", "!!omap {a: 1}", "!!pairs [1]", "!!seq {a: 1}", "!!str 5",
              "!!float 1.5", "!!int 3", "!!null x", "!!binary aGVsbG8=", "!!set {a, b}",
              "!!omap [{a: 1}, {b: 2}]", "!!pairs [{a: 1}]", "!!timestamp 2001-12-14"]
BAD_SCALAR_TAGS = ["!!int abc", "!!float abc", "!!timestamp xyz", "!!bool maybe",
                   "!!int ''", "!!float ''", "!!timestamp 2020-13-45",
                   "!!int " + "9" * 5000]
TAGS = PYTHON_TAGS + OTHER_TAGS + (BAD_SCALAR_TAGS if FULL else [])

BAD_BYTES = [b"\xff", b"\xfe\xff", b"\xc3\x28", b"\x80", b"\xed\xa0\x80", b"\xf8\x88\x80\x80\x80",
             b"\xe9", b"\xc0\xaf", b"\xf4\x90\x80\x80", b"\xe2\x82"]
YAML_JUNK = [":", "[", "]", "{", "}", "&", "*", "!", "%", "@", "`", "|", ">", "\t", "-",
             "? ", "\x00", "\x07", "#", "'", '"', "\n  ", "\n---\n", "\n...\n",
             "&a ", "*a", "*undefined", "<<: *a", "!!", "%YAML 1.1\n---\n"]


def alias_bomb(levels: int, width: int, kind: str):
    """A structure with ``width ** levels`` leaves but only ``levels`` distinct nodes:
    yaml.safe_dump writes it with anchors and aliases ("billion laughs")."""
    node = "lol"
    for _ in range(levels):
        node = [node] * width if kind == "list" else {f"k{j}": node for j in range(width)}
    return node


@st.composite
def hostile_config(draw, cmd):
    """Bytes of a mutated shipped config; the mutations are recorded with note()."""
    from hypothesis import note

    data = copy.deepcopy(BASES[cmd])
    paths, containers = PATHS[cmd], CONTAINERS[cmd]
    tag = None
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["set", "set", "set", "delete", "add", "renest",
                                   "bomb", "share", "tag"]))
        path = draw(st.sampled_from(paths))
        parent = _parent(data, path)
        note(f"{op} at {path}")
        if op == "set" and parent is not None:
            parent[path[-1]] = draw(values)
        elif op == "delete" and parent is not None:
            del parent[path[-1]]
        elif op == "add":
            where = draw(st.sampled_from(containers))
            try:
                box = _lookup(data, where)
            except (KeyError, IndexError, TypeError):
                box = None
            if isinstance(box, dict):
                box[draw(keys | st.integers(-3, 3) | st.none())] = draw(values)
        elif op == "renest" and parent is not None:
            old = parent[path[-1]]
            how = draw(st.sampled_from(["listify", "wrap_list", "wrap_dict", "scalar",
                                        "empty_list", "empty_dict", "null"]))
            parent[path[-1]] = {
                "listify": list(old.values()) if isinstance(old, dict) else [old],
                "wrap_list": [old], "wrap_dict": {"value": old},
                "scalar": draw(scalars), "empty_list": [], "empty_dict": {},
                "null": None}[how]
        elif op == "bomb":
            bomb = alias_bomb(draw(st.integers(2, 9)), draw(st.integers(2, 9)),
                              draw(st.sampled_from(["list", "dict"])))
            if parent is not None and draw(st.booleans()):
                parent[path[-1]] = bomb
            else:
                data[draw(keys)] = bomb
        elif op == "share" and parent is not None:
            other = draw(st.sampled_from(paths))
            try:
                parent[path[-1]] = _lookup(data, other)
            except (KeyError, IndexError, TypeError):
                pass
        elif op == "tag" and parent is not None and tag is None:
            parent[path[-1]] = TAG_PLACEHOLDER
            tag = draw(st.sampled_from(TAGS))
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=draw(st.booleans()),
                          default_flow_style=draw(st.sampled_from([False, None])))
    if tag is not None:
        text = text.replace(TAG_PLACEHOLDER, tag)
    raw = text.encode("utf-8")
    post = draw(st.sampled_from(["none", "none", "none", "bad_bytes", "junk", "truncate",
                                 "crlf", "tabs", "bom", "utf16", "latin1"]))
    note(f"post: {post}")
    if post == "bad_bytes":
        i = draw(st.integers(0, len(raw)))
        raw = raw[:i] + draw(st.sampled_from(BAD_BYTES)) + raw[i:]
    elif post == "junk":
        i = draw(st.integers(0, len(raw)))
        raw = raw[:i] + draw(st.sampled_from(YAML_JUNK)).encode() + raw[i:]
    elif post == "truncate":
        raw = raw[:draw(st.integers(0, len(raw)))]
    elif post == "crlf":
        raw = raw.replace(b"\n", b"\r\n")
    elif post == "tabs":
        raw = raw.replace(b"  ", b"\t")
    elif post == "bom":
        raw = b"\xef\xbb\xbf" + raw
    elif post == "utf16":
        raw = text.encode("utf-16")
    elif post == "latin1":
        raw = (text + "# é\n").encode("latin-1", "replace")
    return raw


OUT_MODES = st.sampled_from(["default", "new", "existing"])


# -- property tests ---------------------------------------------------------------

@FUZZ
@given(raw=hostile_config("run"), out_mode=OUT_MODES)
def test_fuzz_run_config(raw, out_mode, monkeypatch):
    _check_case("run", raw, out_mode, monkeypatch)


@FUZZ
@given(raw=hostile_config("scenario"), out_mode=OUT_MODES)
def test_fuzz_scenario_config(raw, out_mode, monkeypatch):
    _check_case("scenario", raw, out_mode, monkeypatch)


@settings(FUZZ, max_examples=60)
@given(cmd=st.sampled_from(["run", "scenario", "sweep"]), data=st.data())
def test_fuzz_wrong_values_in_fields(cmd, data, monkeypatch):
    """One field at a time: a wrong type, NaN/inf, huge or negative, or deleted."""
    cfg = copy.deepcopy(BASES[cmd])
    path = data.draw(st.sampled_from(PATHS[cmd]), label="path")
    parent = _parent(cfg, path)
    if data.draw(st.integers(0, 9), label="delete?") == 0:
        del parent[path[-1]]
    else:
        parent[path[-1]] = data.draw(scalars | st.lists(scalars, max_size=3), label="value")
    raw = yaml.safe_dump(cfg, sort_keys=False).encode()
    _check_case(cmd, raw, "new", monkeypatch)


@settings(FUZZ, max_examples=60)
@given(cmd=st.sampled_from(["run", "scenario", "sweep"]), data=st.data())
def test_fuzz_python_tags_construct_nothing(cmd, data, monkeypatch):
    cfg = copy.deepcopy(BASES[cmd])
    path = data.draw(st.sampled_from(PATHS[cmd]), label="path")
    _parent(cfg, path)[path[-1]] = TAG_PLACEHOLDER
    tag = data.draw(st.sampled_from(PYTHON_TAGS), label="tag")
    raw = yaml.safe_dump(cfg, sort_keys=False).replace(TAG_PLACEHOLDER, tag).encode()
    # a tag that ran code would create PWNED_* in the working directory, which
    # _check_case's before/after snapshot of that directory catches
    assert _check_case(cmd, raw, "default", monkeypatch) == "refused"


@settings(FUZZ, max_examples=60)
@given(cmd=st.sampled_from(["run", "scenario", "sweep"]), levels=st.integers(2, 9),
       width=st.integers(2, 9), kind=st.sampled_from(["list", "dict"]), data=st.data())
def test_fuzz_alias_bombs_are_refused_quickly(cmd, levels, width, kind, data, monkeypatch):
    cfg = copy.deepcopy(BASES[cmd])
    bomb = alias_bomb(levels, width, kind)
    if data.draw(st.booleans(), label="replace a field?"):
        path = data.draw(st.sampled_from(PATHS[cmd]), label="path")
        _parent(cfg, path)[path[-1]] = bomb
    else:
        cfg[data.draw(keys, label="new key")] = bomb
    raw = yaml.safe_dump(cfg, sort_keys=False).encode()
    assert len(raw) < 20_000 and b"*id" in raw  # small file, expanded only by aliases
    t0 = time.perf_counter()
    _check_case(cmd, raw, "new", monkeypatch)
    assert time.perf_counter() - t0 < MAX_SECONDS


@settings(FUZZ, max_examples=60)
@given(cmd=st.sampled_from(["run", "scenario", "sweep"]), data=st.data())
def test_fuzz_non_utf8_bytes(cmd, data, monkeypatch):
    raw = SHIPPED[cmd].read_bytes()
    for _ in range(data.draw(st.integers(1, 3), label="n")):
        i = data.draw(st.integers(0, len(raw)), label="at")
        raw = raw[:i] + data.draw(st.sampled_from(BAD_BYTES), label="bytes") + raw[i:]
    assert _check_case(cmd, raw, "default", monkeypatch) == "refused"


# -- fixed hostile files ------------------------------------------------------------

def _bomb_text(levels=9, width=9, use="campaign:\n  transitions: *x8\n"):
    lines = ["x0: &x0 [" + ", ".join(["lol"] * width) + "]"]
    lines += [f"x{i}: &x{i} [" + ", ".join([f"*x{i - 1}"] * width) + "]"
              for i in range(1, levels)]
    return "\n".join(lines) + "\n" + use


FIXED = {
    "empty": b"",
    "only_comments": b"# nothing here\n   # still nothing\n\n",
    "only_whitespace": b"   \n\t\n",
    "document_markers": b"---\n...\n",
    "two_documents": b"campaign: {trials: 3}\n---\nmodel: {dt_s: 0.1}\n",
    "top_level_list": b"- campaign\n- model\n",
    "top_level_scalar": b"42\n",
    "top_level_string": b"configs/elevon_lock.yaml\n",
    "latin1": "# réglages\ncampaign:\n  trials: 3\n".encode("latin-1"),
    "utf16": "campaign:\n  trials: 3\n".encode("utf-16"),
    "nul_bytes": b"campaign:\n  trials: 3\x00\n",
    "binary_garbage": bytes(range(256)) * 4,
    "unclosed_flow": b"campaign: {trials: [1, 2\n",
    "undefined_alias": b"campaign: *nowhere\n",
    "python_apply": b"campaign: !!python/object/apply:os.system ['touch PWNED']\n",
    "python_top": b"!!python/object/apply:os.system ['touch PWNED']\n",
    "python_name": b"!!python/name:os.system\n",
    "alias_bomb_unknown_key": _bomb_text(use="").encode(),
    "alias_bomb_transitions": _bomb_text().encode(),
    "alias_bomb_section": _bomb_text(use="campaign: *x8\nscenario: *x8\n").encode(),
    "alias_bomb_schedule": _bomb_text(use="scenario:\n  schedule: *x8\n").encode(),
    "alias_bomb_range": _bomb_text(use="draws:\n  loss_b1_range: *x8\n").encode(),
    "alias_bomb_position": _bomb_text(
        use="scenario:\n  schedule:\n    - {time_s: 0.0, fault: lock, actuator: engine,"
            " position: *x8}\n").encode(),
    "merge_bomb": ("m0: &m0 {a: 1}\n" + "".join(
        f"m{i}: &m{i} {{<<: [{', '.join([f'*m{i - 1}'] * 9)}]}}\n" for i in range(1, 9))
        + "campaign: {<<: *m8}\n").encode(),
    "nested_400": ("campaign: " + "[" * 400 + "]" * 400 + "\n").encode(),
    "many_keys": "".join(f"k{i}: {i}\n" for i in range(5_000)).encode(),
}


@pytest.mark.parametrize("cmd", ["run", "scenario"])
@pytest.mark.parametrize("name", sorted(FIXED))
def test_hostile_file(cmd, name, monkeypatch):
    assert _check_case(cmd, FIXED[name], "default", monkeypatch) == "refused"


def _special_path(kind, tmp_path):
    if kind == "directory":
        p = tmp_path / "configs_dir.yaml"
        p.mkdir()
    elif kind == "missing":
        p = tmp_path / "nope.yaml"
    elif kind == "dangling_symlink":
        p = tmp_path / "dangling.yaml"
        p.symlink_to(tmp_path / "nowhere.yaml")
    elif kind == "symlink_loop":
        p = tmp_path / "loop.yaml"
        p.symlink_to(p)
    elif kind == "symlink_to_dir":
        (tmp_path / "d").mkdir()
        p = tmp_path / "link.yaml"
        p.symlink_to(tmp_path / "d")
    elif kind == "fifo":
        p = tmp_path / "fifo.yaml"
        os.mkfifo(p)
    elif kind == "dev_null":
        p = Path(os.devnull)
    elif kind == "file_as_parent":
        (tmp_path / "f").write_text("")
        p = tmp_path / "f" / "c.yaml"
    return p


@pytest.mark.parametrize("cmd", ["run", "scenario"])
@pytest.mark.parametrize("kind", ["directory", "missing", "dangling_symlink", "symlink_loop",
                                  "symlink_to_dir", "fifo", "dev_null", "file_as_parent"])
def test_not_a_config_file(cmd, kind, tmp_path, monkeypatch):
    if kind == "fifo" and not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    work = tmp_path / "work"
    work.mkdir()
    path = _special_path(kind, tmp_path)
    before = _snapshot(tmp_path)
    monkeypatch.chdir(work)
    t0 = time.perf_counter()
    res = CliRunner().invoke(cli, [cmd, str(path), "--out", str(tmp_path / "out")])
    _assert_refused(cmd, path, None, res, time.perf_counter() - t0, before,
                    _snapshot(tmp_path), work)
    assert not list(work.iterdir())


def test_shipped_configs_are_valid_and_mutations_start_from_them():
    assert _oracle("run", SHIPPED["run"].read_bytes())[0]
    assert _oracle("scenario", SHIPPED["scenario"].read_bytes())[0]
    assert ("campaign", "trials") in PATHS["run"]
    assert ("scenario", "schedule", 5, "position") in PATHS["scenario"]


# -- regressions: bugs the fuzzing found in config handling, now fixed --------------

def _refused_cleanly(cmd, raw, tmp_path, monkeypatch, name="config.yaml"):
    """Like _check_case but without the validity oracle (which may itself crash)."""
    work = tmp_path / "work"
    work.mkdir()
    path = tmp_path / name
    path.write_bytes(raw)
    res, elapsed, before, after = _invoke(cmd, path, "new", monkeypatch, work)
    try:
        data = yaml.safe_load(raw.decode())
    except Exception:  # noqa: BLE001
        data = None
    _assert_refused(cmd, path, data, res, elapsed, before, after, work)


BUG_OVERFLOW = {
    "run_duration_1e308": ("run", b"timing:\n  duration_s: 1.0e+308\n"),
    "run_dt_subnormal": ("run", b"model:\n  dt_s: 5.0e-324\n"),
    "scenario_time_1e307": ("scenario", b"scenario:\n  duration_s: 1.0e+308\n  schedule:\n"
                            b"    - {time_s: 0.0, fault: nominal}\n"
                            b"    - {time_s: 1.0e+307, fault: nominal}\n"),
    "scenario_duration_1e308": ("scenario", b"scenario:\n  duration_s: 1.0e+308\n"),
    "scenario_dt_subnormal": ("scenario", b"model:\n  dt_s: 5.0e-324\n"),
}


@pytest.mark.parametrize("case", sorted(BUG_OVERFLOW))
def test_regression_overflow_in_step_checks(case, tmp_path, monkeypatch):
    cmd, raw = BUG_OVERFLOW[case]
    _refused_cleanly(cmd, raw, tmp_path, monkeypatch)


@pytest.mark.parametrize("cmd", ["run", "scenario"])
@pytest.mark.parametrize("opener,closer", [("[", "]"), ("{a: ", "}")])
def test_regression_deep_nesting(cmd, opener, closer, tmp_path, monkeypatch):
    raw = ("campaign: " + opener * 1000 + "1" + closer * 1000 + "\n").encode()
    _refused_cleanly(cmd, raw, tmp_path, monkeypatch)


@pytest.mark.parametrize("cmd", ["run", "scenario"])
@pytest.mark.parametrize("tag", BAD_SCALAR_TAGS)
def test_regression_bad_tagged_scalars(cmd, tag, tmp_path, monkeypatch):
    _refused_cleanly(cmd, f"campaign:\n  seed: {tag}\n".encode(), tmp_path, monkeypatch)


@pytest.mark.parametrize("tag", ["!!pairs", "!!omap"])
def test_regression_alias_bomb_echoed_through_tuple(tag, tmp_path, monkeypatch):
    raw = _bomb_text(levels=6, use=f"draws:\n  engine_lock_range: {tag} [{{a: *x5}}]\n")
    _refused_cleanly("run", raw.encode(), tmp_path, monkeypatch)


@pytest.mark.parametrize("cmd", ["run", "scenario"])
def test_regression_huge_value_echoed(cmd, tmp_path, monkeypatch):
    section = "campaign" if cmd == "run" else "scenario"
    raw = f"{section}:\n  signature: {'x' * 1_000_000}\n".encode()
    _refused_cleanly(cmd, raw, tmp_path, monkeypatch)


@pytest.mark.parametrize("cmd", ["run", "scenario"])
def test_regression_file_name_too_long(cmd, tmp_path, monkeypatch):
    path = tmp_path / ("a" * 300 + ".yaml")
    work = tmp_path / "work"
    work.mkdir()
    before = _snapshot(tmp_path)
    monkeypatch.chdir(work)
    res = CliRunner().invoke(cli, [cmd, str(path), "--out", str(tmp_path / "out")])
    _assert_refused(cmd, path, None, res, 0.0, before, _snapshot(tmp_path), work)


@pytest.mark.parametrize("section,field", [("campaign", "trials"), ("campaign", "seed"),
                                           ("model", "airspeed_mps"),
                                           ("noise", "process_scale")])
def test_regression_yaml_booleans_accepted_as_numbers(section, field):
    with pytest.raises(UserError, match=f"{section}.{field}"):
        parse_config({section: {field: True}})
