"""The one place that sets how every kernel is compiled.

Compiled kernels are cached on disk (``docs/findings/performance.md``, lesson 6), keyed
on the content of every kernel source.  Numba on its own keys a cached kernel on
its own file only (its folder on the file's absolute path, its stamp on that
file alone), so a kernel that inlines others would be loaded stale after an edit of
theirs, and a second clone of the same sources would compile everything again.
Here instead (:class:`ContentCacheLocator`, the first locator of each kernel's
cache, :class:`ContentFunctionCache`), a kernel defined under ``ftc_mc/core/`` is cached in a folder named
after a digest of the kernel sources (:func:`source_digest`: every ``.py`` file
under ``core/``, read recursively, and the modules outside it that they import,
such as ``conventions.py``), and its index is stamped with that digest:
``$FTC_MC_CACHE_DIR/numba/<digest>/core/`` (``~/.cache/ftc-mc/numba/<digest>``
by default).  No path of the clone enters the folder or the stamp, so another
clone or install of identical sources loads the kernels, while any edit of a
kernel source starts a new folder.  A process whose kernel sources change while
it runs saves no kernel (:func:`sources_unchanged`), and a kernel whose cache
folder cannot be written is not cached (Numba's own locators, keyed on the
kernel's file alone, are not tried for the kernels of ``core/``).  A kernel of a
source tree's own ``tests/`` or ``scripts/`` is keyed the same way, on the kernel
sources and on those folders' files (:class:`CloneFolderLocator`), so a new
clone loads the test kernels too.  ``NUMBA_CACHE_DIR`` in the environment takes
precedence over ``$FTC_MC_CACHE_DIR/numba`` (``$NUMBA_CACHE_DIR/<digest>``; the
benchmarks point it at an empty folder), and ``FTC_MC_NUMBA_CACHE=0`` turns caching off.
A cache the installed Numba cannot use (an index of another Numba version, a
file that does not unpickle) is a cache miss, said in one line on stderr
(:class:`TolerantIndexFile`, :meth:`ContentFunctionCache.load_overload`).  ``fastmath`` stays
off: it was no faster here (``scripts/benchmarks/bench_core.py``) and breaks bit-for-bit
agreement with the NumPy references.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import io
import os
import pickle
from pathlib import Path

import numba
from numba.core import caching, sigutils
from numba.core.registry import CPUDispatcher

from .linking import ByAddressCacheImpl, route_calls

CACHE = os.environ.get("FTC_MC_NUMBA_CACHE", "1") != "0"

CORE = Path(__file__).resolve().parent
"""This package's kernel folder, ``ftc_mc/core``."""


def _module_file(target: Path) -> Path | None:
    """The file of the module at ``target`` (a path without suffix): the
    module ``target.py`` or the package ``target/__init__.py``."""
    for cand in (target.parent / (target.name + ".py"), target / "__init__.py"):
        if cand.is_file():
            return cand
    return None


@functools.lru_cache(maxsize=None)
def _imported_files(path: Path, package: Path, size: int, mtime_ns: int) -> frozenset:
    """The files of modules inside ``package`` (the ``ftc_mc`` folder) that the
    module at ``path`` imports anywhere in its body: relative imports, and
    absolute ones that start with the package's name.  (``size`` and
    ``mtime_ns``, the file's stamp, key the memo.)"""
    try:
        tree = ast.parse(path.read_bytes(), filename=str(path))
    except (OSError, SyntaxError, ValueError):
        return frozenset()
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = path.parent
                for _ in range(node.level - 1):
                    base = base.parent
            elif node.module and node.module.split(".")[0] == package.name:
                base = package.parent
            else:
                continue
            module = base.joinpath(*node.module.split(".")) if node.module else base
            # ``from module import name``: a submodule, or a name defined in module
            names_in_module = False
            for alias in node.names:
                sub = _module_file(module / alias.name) if alias.name != "*" else None
                if sub is not None:
                    found.add(sub)
                else:
                    names_in_module = True
            if names_in_module and _module_file(module) is not None:
                found.add(_module_file(module))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == package.name and _module_file(package.parent.joinpath(*parts)):
                    found.add(_module_file(package.parent.joinpath(*parts)))
    return frozenset(f.resolve() for f in found if f.resolve().is_relative_to(package))


def kernel_sources(core: Path | None = None) -> list[Path]:
    """Every file the kernels compile from: each ``.py`` file under ``core``
    (this package's ``ftc_mc/core`` by default), read recursively, and every
    module inside the package that one of them imports, followed on through
    their own imports (``conventions.py`` today).  Sorted by path."""
    core = CORE if core is None else Path(core).resolve()
    package = core.parent
    files = {p for p in core.rglob("*.py") if "__pycache__" not in p.parts}  # core: resolved
    queue = sorted(files)
    while queue:
        path = queue.pop()
        st = path.stat()
        for dep in _imported_files(path, package, st.st_size, st.st_mtime_ns):
            if dep not in files:
                files.add(dep)
                queue.append(dep)
    return sorted(files, key=lambda p: p.relative_to(package).as_posix())


_DIGESTS: dict = {}

_FIRST_STATS: dict = {}
"""Per kernel folder, the stamps of its sources when this process first read
them (:func:`sources_unchanged`)."""


def _stats(files) -> tuple:
    """(path, size, modification time) of each of ``files``."""
    return tuple((str(p), st.st_size, st.st_mtime_ns) for p in files for st in [p.stat()])


def _source_stats(core: Path) -> tuple:
    """:func:`_stats` of every file of :func:`kernel_sources`."""
    return _stats(kernel_sources(core))


def _content_digest(base: Path, stats: tuple) -> str:
    """SHA-256 (hex) of the path relative to ``base`` and the content of every
    file of ``stats`` (:func:`_stats`); read again only when a file's stamp
    (size, modification time) or the list of files changes."""
    key = (str(base), stats)
    if key not in _DIGESTS:
        h = hashlib.sha256()
        for path in (Path(name) for name, _, _ in stats):
            h.update(path.relative_to(base).as_posix().encode() + b"\0")
            data = path.read_bytes()
            h.update(len(data).to_bytes(8, "little") + data)
        _DIGESTS[key] = h.hexdigest()
    return _DIGESTS[key]


def full_source_digest(core: Path | None = None) -> str:
    """:func:`_content_digest` of every file of :func:`kernel_sources`, paths
    relative to the package's parent folder."""
    core = CORE if core is None else Path(core).resolve()
    stats = _source_stats(core)
    _FIRST_STATS.setdefault(str(core), stats)
    return _content_digest(core.parent, stats)


def sources_unchanged(core: Path | None = None) -> bool:
    """Whether the kernel sources still have the stamps (size, modification
    time) they had when this process first read them, and no file came or went.

    A process that imports some kernel modules, and others after an edit (a
    lazily imported module, a ``git checkout`` during a test run), compiles
    kernels that mix old and new code.  Their folder and stamp are those of one
    digest or the other, so a later process of either sources would load them:
    :class:`ContentFunctionCache` does not save a kernel once this is false.
    """
    core = CORE if core is None else Path(core).resolve()
    first = _FIRST_STATS.get(str(core))
    if first is None:
        return True
    try:
        return _source_stats(core) == first
    except OSError:  # a source (or one it imports) went while it was listed
        return False


def source_digest(core: Path | None = None) -> str:
    """The first 16 hex digits of :func:`full_source_digest`: the name of the
    kernel cache folder of these sources."""
    return full_source_digest(core)[:16]


def clone_sources(root: Path) -> list[Path]:
    """The ``.py`` files directly inside a source tree's ``root`` and at any
    depth inside each of its folders whose name does not start with a dot
    (``tests/``, ``scripts/benchmarks/``), but for folders whose name starts
    with a dot; the package (``ftc_mc/``) is left out, its kernels being
    :func:`kernel_sources`.  Sorted by path."""
    files = list(root.glob("*.py"))
    for folder in root.iterdir():
        if folder.is_dir() and not folder.name.startswith(".") and folder != CORE.parent:
            files += (f for f in folder.rglob("*.py")
                      if not any(part.startswith(".") for part in f.relative_to(root).parts))
    return sorted(files, key=lambda p: p.relative_to(root).as_posix())


def clone_digest(root: Path) -> str:
    """:func:`_content_digest` of every file of :func:`clone_sources`, paths
    relative to ``root``."""
    return _content_digest(root, _stats(clone_sources(root)))


def cache_root() -> Path:
    """The folder of every source's kernel cache: ``NUMBA_CACHE_DIR`` if set,
    else ``$FTC_MC_CACHE_DIR/numba``, else ``~/.cache/ftc-mc/numba``."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    root = os.environ.get("FTC_MC_CACHE_DIR") or Path.home() / ".cache" / "ftc-mc"
    return Path(root) / "numba"


def cache_dir() -> Path:
    """The folder of the compiled kernels of this source (module docstring):
    ``cache_root() / source_digest()``."""
    return cache_root() / source_digest()


def _resolved(py_file) -> Path | None:
    """The resolved path of a kernel's file, or None when it is not a file."""
    try:
        path = Path(py_file).resolve()
    except (OSError, TypeError, ValueError):
        return None
    return path if path.is_file() else None


class ContentCacheLocator(caching._CacheLocator):
    """Numba cache locator for the kernels defined under :data:`CORE`.

    The cache folder is ``cache_dir() / <the module's folder inside the
    package>`` (``core``, ``core/<subpackage>``), and the source stamp of the
    index is :func:`full_source_digest`: both follow the content of every
    kernel source and neither holds the clone's path.  Functions defined
    elsewhere are left to Numba's own locators (``from_function`` returns
    ``None``).
    """

    def __init__(self, py_func, py_file: Path, core: Path):
        self._lineno = py_func.__code__.co_firstlineno
        self._core = core
        self._stamp = full_source_digest(core)
        sub = py_file.parent.relative_to(core.parent).as_posix()
        self._cache_path = str(cache_root() / self._stamp[:16] / sub)

    def sources_unchanged(self) -> bool:
        """Whether what this locator was keyed on is unchanged since the
        process first read it (:func:`sources_unchanged`)."""
        return sources_unchanged(self._core)

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return self._stamp

    def get_disambiguator(self):
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file):
        path = _resolved(py_file)
        if path is None or not path.is_relative_to(CORE):
            return None
        return cls._writable(py_func, path)

    @classmethod
    def _writable(cls, py_func, path: Path):
        """The locator of ``py_func`` (defined in ``path``), its folder created;
        :class:`CacheUnavailable` when it cannot be written."""
        self = cls(py_func, path, CORE)
        try:
            self.ensure_cache_path()
        except OSError as exc:
            # not writable: no disk cache for this kernel.  Numba's own locators
            # (next in the list) would stamp it with its own file only, so a
            # later process would load it stale after an edit of a kernel it
            # inlines (:func:`_njit` leaves the kernel uncached)
            raise CacheUnavailable(f"{self._cache_path}: {exc}") from exc
        return self


class PythonTwinLocator(ContentCacheLocator):
    """:class:`ContentCacheLocator` of the twin an internal kernel compiles
    for calls from Python (:class:`InternalKernel`): its own index beside the
    kernel's (``<kernel>-<line>-python``), since Numba's index keys hold the
    signature and not the wrappers, so the two would overwrite each other's
    entries."""

    def get_disambiguator(self):
        return super().get_disambiguator() + "-python"


class CloneFolderLocator(ContentCacheLocator):
    """Numba cache locator for the kernels of a source tree's own folders:
    functions defined in a file of ``tests/`` or ``scripts/`` (at any depth)
    beside ``ftc_mc/`` in a tree with ``pyproject.toml`` (a clone, not an install).

    Numba's own locator keys such a kernel on its file's absolute path and its
    file's stamp alone: a new clone compiles every test kernel again (15 s of
    the test suite's CPU, measured), and an edit of a file it inlines
    (``tests/single_trajectory.py`` from ``tests/test_soak.py``) would load it
    stale.  Here the folder and the stamp follow the content of the kernel
    sources (:func:`full_source_digest`) and of every file of
    :func:`clone_sources`: ``cache_dir() / "clone" / <digest> / <folder>``.
    A folder that cannot be written leaves the kernel uncached, as for ``core/``.
    """

    def __init__(self, py_func, py_file: Path, core: Path):
        self._lineno = py_func.__code__.co_firstlineno
        self._core, self._root = core, core.parent.parent
        self._clone = clone_digest(self._root)
        self._stamp = full_source_digest(core) + self._clone
        self._cache_path = str(cache_root() / self._stamp[:16] / "clone" / self._clone[:16]
                               / py_file.parent.relative_to(self._root))

    def sources_unchanged(self) -> bool:
        """Whether the kernel sources and the tree's own files still have the
        content this locator was keyed on."""
        return super().sources_unchanged() and self._clone == clone_digest(self._root)

    @classmethod
    def from_function(cls, py_func, py_file):
        path = _resolved(py_file)
        root = CORE.parent.parent
        if path is None or not path.is_relative_to(root) or path.parent == root:
            return None
        parts = path.relative_to(root).parts
        if (parts[0] == CORE.parent.name or any(p.startswith(".") for p in parts[:-1])
                or not (root / "pyproject.toml").is_file()):
            return None
        return cls._writable(py_func, path)


class CacheUnavailable(RuntimeError):
    """The content-keyed cache folder of a kernel of :data:`CORE` cannot be
    written (:meth:`ContentCacheLocator.from_function`)."""


class ContentCacheImpl(ByAddressCacheImpl):
    """The cache implementation of Numba's ``FunctionCache`` (with the stages
    a kernel calls by address, :class:`~ftc_mc.core.linking.ByAddressCacheImpl`),
    with :class:`ContentCacheLocator` and :class:`CloneFolderLocator` tried
    before Numba's own locators."""

    _locator_classes = [ContentCacheLocator, CloneFolderLocator,
                        *caching.FunctionCache._impl_class._locator_classes]


class PythonTwinCacheImpl(ByAddressCacheImpl):
    """The cache implementation of an internal kernel's twin: only
    :class:`PythonTwinLocator` (outside :data:`CORE` no locator is found, and
    the twin is not cached)."""

    _locator_classes = [PythonTwinLocator]


CLAIM_WAIT_LIMIT_S = 900.0
"""Longest wait for a kernel another process has claimed [s]
(:meth:`ContentFunctionCache.load_overload`); then this process compiles it."""


def _claim_held(fd: int) -> bool:
    """Whether another process holds the ``flock`` of the open claim ``fd``."""
    import fcntl
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    fcntl.flock(fd, fcntl.LOCK_UN)
    return False


class _ForeignType:
    """Stands in, while a cache index is read, for a class of a module this
    process cannot import (:class:`TolerantIndexFile`); built from whatever
    the pickle holds."""

    def __new__(cls, *args, **kwargs):
        return object.__new__(cls)

    def __init__(self, *args, **kwargs):
        pass

    def __setstate__(self, state):
        pass


class _TolerantUnpickler(pickle.Unpickler):
    """Numba's index unpickler, but a class of a module this process cannot
    import (a test's namedtuple passed to a package kernel) becomes a subclass
    of :class:`_ForeignType`, which no live signature equals."""

    def find_class(self, module, name):
        try:
            return super().find_class(module, name)
        except (ImportError, AttributeError):
            return type(name, (_ForeignType,), {"__module__": module})


def _native(key) -> bool:
    """Whether a cache index key holds no :class:`_ForeignType` (it pickles)."""
    try:
        pickle.dumps(key)
    except Exception:  # noqa: BLE001 -- a stand-in class pickles by a name that is not there
        return False
    return True


CACHE_MISMATCH_NOTICE = ("ftc-mc: the kernel cache in {} was written by Numba {}, this is "
                         "Numba {}; its kernels are compiled again (same results)")
"""Printed to stderr, once per process, when a kernel's cache index is of
another Numba version (Numba itself then reads it as empty)."""

CACHE_UNREADABLE_NOTICE = ("ftc-mc: a kernel cache file in {} cannot be read with this "
                           "Numba ({}); its kernels are compiled again (same results)")
"""Printed to stderr, once per process, when a kernel's cache index or
compiled kernel cannot be read (damaged, or of a Numba whose classes moved):
it is then a cache miss, and the kernel is compiled and saved anew."""

_CACHE_NOTICED = False


def _cache_notice(text: str) -> None:
    """Print ``text`` to stderr, one line, unless a cache notice was printed
    in this process already."""
    global _CACHE_NOTICED
    if _CACHE_NOTICED:
        return
    _CACHE_NOTICED = True
    import sys
    print(" ".join(text.split()), file=sys.stderr, flush=True)


def _why(exc: BaseException) -> str:
    """A short one-line description of ``exc`` for a notice."""
    text = " ".join(f"{type(exc).__name__}: {exc}".split())
    return text if len(text) <= 120 else text[:117] + "..."


class TolerantIndexFile(caching.IndexDataCacheFile):
    """A kernel's cache index that stays readable in a process that cannot import
    a type some other process compiled the kernel for (the tests compile package
    kernels on types of their own modules; a process without ``tests/`` on its
    path failed to load such an index at all).  Those entries are left out of
    what this process reads, so they are a cache miss here and are dropped when
    this process saves an overload of the kernel.

    An index that cannot be read at all (damaged, or pickled by a Numba whose
    classes this one lacks) is read as empty, with one line on stderr
    (:data:`CACHE_UNREADABLE_NOTICE`): its kernels are compiled and the index
    written anew.  One of another Numba version, which Numba reads as empty,
    is said so too (:data:`CACHE_MISMATCH_NOTICE`)."""

    def _load_index(self):
        try:
            overloads = super()._load_index()
        except (ImportError, AttributeError):
            try:
                return self._load_tolerant()
            except Exception as exc:  # noqa: BLE001 -- unreadable: a miss
                return self._unreadable(exc)
        except Exception as exc:  # noqa: BLE001 -- unreadable: a miss
            return self._unreadable(exc)
        if not overloads:
            self._check_version()
        return overloads

    def _load_tolerant(self) -> dict:
        """The index with the entries of types this process cannot import
        left out (class docstring)."""
        with open(self._index_path, "rb") as f:
            pickle.load(f)  # the version, checked by the first attempt
            stamp, overloads = _TolerantUnpickler(io.BytesIO(f.read())).load()
        if stamp != self._source_stamp:
            return {}
        return {k: v for k, v in overloads.items() if _native(k)}

    def _unreadable(self, exc: BaseException) -> dict:
        _cache_notice(CACHE_UNREADABLE_NOTICE.format(self._cache_path, _why(exc)))
        return {}

    def _check_version(self) -> None:
        """Say so (once) if the index on disk is of another Numba version."""
        try:
            with open(self._index_path, "rb") as f:
                version = pickle.load(f)
        except Exception:  # noqa: BLE001 -- no index (a miss) or unreadable: nothing to say
            return
        if version != self._version:
            _cache_notice(CACHE_MISMATCH_NOTICE.format(self._cache_path, version,
                                                       self._version))


class ContentFunctionCache(caching.FunctionCache):
    """The on-disk cache of one kernel (:func:`kernel`): Numba's, located by
    :class:`ContentCacheImpl`, that saves nothing once the kernel sources have
    changed while this process ran (:func:`sources_unchanged`), and says so once
    on stderr.

    A process that compiles part of a path for another (the compile helper,
    :mod:`ftc_mc.sim.compile_helper`) *claims* each kernel signature it will
    compile: it holds ``flock`` on the file :meth:`claim_path` until the
    kernel is saved.  Before loading or compiling a signature,
    :meth:`load_overload` waits while its claim is held (at most
    :data:`CLAIM_WAIT_LIMIT_S`), so the kernel is loaded from the cache instead
    of compiled twice.  A claim no live process holds is not waited for, and a
    process that claims waits for no claim (:attr:`awaits_claims`), so waits
    never form a cycle.
    """

    _impl_class = ContentCacheImpl
    _warned = False
    awaits_claims = True

    def __init__(self, py_func):
        super().__init__(py_func)
        self._cache_file.__class__ = TolerantIndexFile
    """Whether this process waits for claims; a compile helper, which holds
    claims, does not (so two helpers never wait for each other)."""

    def claim_path(self, sig) -> Path:
        """The claim file of the signature ``sig`` (argument types) of this
        kernel: in its cache folder, named after the kernel, its line and a
        digest of the signature's text."""
        args, _ = sigutils.normalize_signature(sig)
        digest = hashlib.sha256(str(tuple(args)).encode()).hexdigest()[:16]
        f = self._py_func
        name = f"{f.__module__}.{f.__qualname__}-{f.__code__.co_firstlineno}"
        return Path(self._cache_path) / f"{name}.{digest}.claim"

    def load_overload(self, sig, target_context):
        """Numba's, after waiting for a claim (class docstring); a compiled
        kernel that cannot be loaded (a damaged file, a Numba whose internals
        moved) is a cache miss, said once on stderr
        (:data:`CACHE_UNREADABLE_NOTICE`): the kernel is compiled, and saved
        over it."""
        self._await_claim(sig)
        try:
            return super().load_overload(sig, target_context)
        except Exception as exc:  # noqa: BLE001 -- unreadable: compile instead
            _cache_notice(CACHE_UNREADABLE_NOTICE.format(self._cache_path, _why(exc)))
            return None

    def _await_claim(self, sig) -> None:
        """Wait while another process holds the claim of ``sig`` (class docstring)."""
        import time
        if not self.awaits_claims:
            return
        try:
            fd = os.open(self.claim_path(sig), os.O_RDONLY)
        except (OSError, ValueError, TypeError):
            return  # no claim (or no claim can be named): nothing to wait for
        try:
            deadline = time.monotonic() + CLAIM_WAIT_LIMIT_S
            while _claim_held(fd) and time.monotonic() < deadline:
                time.sleep(0.02)
        except (ImportError, OSError):
            pass  # no flock here: compile without waiting
        finally:
            os.close(fd)

    def _save_overload(self, sig, data):
        """Save, unless the sources changed (class docstring), under an
        ``flock`` of ``<index>.lock``: Numba reads, extends and rewrites a
        kernel's index unlocked, so two processes saving overloads of one
        kernel at once (a compile helper and this one) could lose an entry or
        give two the same data file."""
        locator = self._impl.locator
        if not (locator.sources_unchanged() if isinstance(locator, ContentCacheLocator)
                else sources_unchanged()):
            if not ContentFunctionCache._warned:
                import sys
                print("ftc-mc: the kernel sources changed while this process ran; "
                      "its compiled kernels are not cached", file=sys.stderr, flush=True)
                ContentFunctionCache._warned = True
            return
        try:
            import fcntl
            fd = os.open(self._cache_file._index_path + ".lock", os.O_CREAT | os.O_RDWR, 0o644)
        except (ImportError, OSError, AttributeError):
            return super()._save_overload(sig, data)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            super()._save_overload(sig, data)
        finally:
            os.close(fd)


if CACHE:
    full_source_digest()  # the stamps every later save is checked against
    if not os.environ.get("NUMBA_CACHE_DIR"):
        # kernels compiled with cache=True outside core/ and outside a source
        # tree's own folders, and the compile lock (sim.compiling), use Numba's
        # own setting
        numba.config.CACHE_DIR = str(cache_dir())

OPTIONS = dict(cache=CACHE, fastmath=False, nogil=True, error_model="numpy")

NO_WRAPPERS = dict(no_cpython_wrapper=True, no_cfunc_wrapper=True)
"""Numba's options that leave out a kernel's CPython and C wrappers: the code
that unboxes its arguments from Python objects (for a kernel taking the
scheme, the lane state and the work arrays, several hundred arrays), compiled
with the kernel and again in every kernel that calls it (:func:`kernel`'s
``internal``)."""


def kernel(func=None, *, internal=False, by_address=False, **overrides):
    """``numba.njit`` with the project's defaults (see module docstring).

    Parameters
    ----------
    func : callable, optional
        Function to compile; when omitted, returns a decorator.
    internal : bool
        The kernel is called by other kernels only: it is compiled without
        its Python wrappers (:data:`NO_WRAPPERS`), which shortens every
        path's cold compile (``docs/findings/performance.md``, lesson 14).  A call
        from Python still works: it compiles a twin with its
        wrappers once (cached beside the kernel, :class:`InternalKernel`).
    by_address : bool
        An internal kernel (implied) that other kernels call by address,
        without linking its code into theirs (:mod:`ftc_mc.core.linking`):
        for a stage called once per step, not for a helper called per lane
        or a small kernel LLVM would inline into its caller (the paper
        filter's lane kernels ``project_lanes``, ``_symmetric_copy``,
        ``reset_lanes`` and ``_normalised_lanes`` by address cost
        ``bench_core``'s batch filter about 6 %; ``docs/findings/performance.md``
        lessons 12 and 17).
    **overrides
        Options that replace the defaults for this kernel.
    """
    opts = dict(OPTIONS, **overrides)
    if func is None:
        return lambda f: _njit(f, opts, internal or by_address, by_address=by_address)
    return _njit(func, opts, internal or by_address, by_address=by_address)


def _njit(func, opts, internal=False, python_twin=False, by_address=False):
    """``numba.njit(**opts)(func)``, its disk cache a :class:`ContentFunctionCache`
    (the twin of an internal kernel: :class:`PythonTwinCache`); an internal
    kernel without its wrappers, an :class:`InternalKernel`."""
    opts = dict(opts)
    cache = opts.pop("cache")
    dispatcher = numba.njit(**opts, **(NO_WRAPPERS if internal else {}))(func)
    if internal:
        dispatcher.__class__ = InternalKernel
        dispatcher._kernel_opts = dict(opts, cache=cache)
        dispatcher._by_address = by_address
    if cache:
        try:
            # Dispatcher.enable_caching
            dispatcher._cache = (PythonTwinCache if python_twin else ContentFunctionCache)(func)
        except CacheUnavailable as exc:  # compiled in every process
            global _UNCACHED_WARNED
            if not _UNCACHED_WARNED:
                import sys
                print(f"ftc-mc: the kernel cache folder cannot be written ({exc}); "
                      "the kernels are compiled in every process (set FTC_MC_CACHE_DIR "
                      "to a writable folder)", file=sys.stderr, flush=True)
                _UNCACHED_WARNED = True
        except RuntimeError:  # Numba's "no locator available"
            if not python_twin:
                raise
            # the twin of a kernel outside core/: not cached (PythonTwinCacheImpl)
    return dispatcher


_UNCACHED_WARNED = False


class InternalKernel(CPUDispatcher):
    """The dispatcher of a kernel compiled without its Python wrappers
    (``kernel(internal=True)``).  Other kernels call it as any kernel.  Called
    from Python (a test, a notebook), it hands the call to a twin compiled from
    the same function with the same options and its wrappers, made on the
    first such call: without them, Numba's dispatcher would call a null
    entry point.  With ``kernel(by_address=True)``, every overload it compiles
    or loads is called by address by the kernels compiled after it
    (:func:`ftc_mc.core.linking.route_calls`)."""

    _by_address = False

    def add_overload(self, cres):
        super().add_overload(cres)
        if self._by_address and not cres.objectmode:
            route_calls(self, cres)

    def __call__(self, *args, **kwargs):
        twin = self.__dict__.get("_python_twin")
        if twin is None:
            opts = getattr(self, "_kernel_opts", OPTIONS)
            twin = self._python_twin = _njit(self.py_func, opts, python_twin=True)
        return twin(*args, **kwargs)


COMPILE_NOTICE = ("ftc-mc: compiling the simulation kernels of this path once: {} "
                  "(about {} on 2 cores; later runs start at once)")
"""Printed to stderr before the first run that compiles a path of the trial kernel
(``core/shared/paths.py``)."""

COMPILE_NOTICE_NO_CACHE = ("ftc-mc: compiling the simulation kernels of this path: {} "
                           "(about {} on 2 cores; FTC_MC_NUMBA_CACHE=0, so every run "
                           "compiles)")

COMPILED_NOTICE = "ftc-mc: compiled in {:.1f} s"
"""Printed to stderr when that compile is done, with its measured duration."""


def index_has_overload(index_keys, magic, code_hash) -> bool:
    """Whether a Numba cache index holds an overload for this machine and code.

    Parameters
    ----------
    index_keys : iterable
        Keys of the index (``(signature, codegen magic tuple, (code hash,
        closure hash))``, ``numba.core.caching.Cache._index_key``); empty when
        the index is missing or stale (its source stamp differs).
    magic : tuple
        The codegen's magic tuple (target triple, CPU name, features).
    code_hash : str
        SHA-256 hex digest of the function's bytecode.
    """
    for key in index_keys:
        try:
            _, key_magic, (key_code, _) = key
        except (TypeError, ValueError):
            continue
        if key_magic == magic and key_code == code_hash:
            return True
    return False


def in_disk_cache(dispatcher, first=None) -> bool | None:
    """Whether Numba's on-disk cache holds an overload of ``dispatcher`` for this
    machine and source (so calling it loads instead of compiling).

    Reads the cache index the way Numba's ``FunctionCache`` does (the source
    stamp of the function's file, then the key's target and bytecode hash).
    Of the signature, only the first argument's type is checked, when
    ``first`` gives it (the trial kernel's compile path, ``core/shared/paths.py``):
    the campaign, sweep and scenario call each path with one and the same
    signature.  Returns ``None`` when the cache's layout is not the expected
    one (a Numba version that changed it).
    """
    import hashlib
    try:
        index = dispatcher._cache._cache_file._load_index()
        magic = dispatcher.targetctx.codegen().magic_tuple()
    except Exception:  # noqa: BLE001 -- numba internals; the notice is optional
        return None
    code_hash = hashlib.sha256(dispatcher.py_func.__code__.co_code).hexdigest()
    keys = [k for k in index.keys() if first is None or _first_arg(k) == first]
    return index_has_overload(keys, magic, code_hash)


def cached_signature(dispatcher, sig) -> bool:
    """Whether Numba's on-disk cache holds ``dispatcher``'s overload for the
    signature ``sig`` (argument types) on this machine and source; False when
    that cannot be told."""
    try:
        cache = dispatcher._cache
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 -- numba internals; then it is compiled
        return False


def _first_arg(key):
    """The first argument's type of a cache index key's signature, or None."""
    try:
        return key[0][0]
    except (TypeError, IndexError):
        return None


def needs_compile(dispatcher, first=None) -> bool | None:
    """Whether calling ``dispatcher`` will compile it: no overload in this
    process and none in the on-disk cache (:func:`in_disk_cache`); with
    ``first``, none whose first argument has that Numba type.  ``None`` when
    that cannot be told (then nothing is announced)."""
    if any(first is None or sig[0] == first for sig in dispatcher.signatures):
        return False
    if not CACHE:
        return True
    cached = in_disk_cache(dispatcher, first)
    return None if cached is None else not cached


def announce_compile(dispatcher, what="", duration="1 min", stream=None,
                     needed=None) -> bool:
    """Print :data:`COMPILE_NOTICE` to stderr if ``dispatcher`` is about to be
    compiled (:func:`needs_compile`, or ``needed`` when the caller has just
    asked it); return whether it was printed.

    ``what`` names the path compiled, ``duration`` the time it takes (the
    measured figures per path, and why they are less when the kernels they
    share are cached: ``docs/findings/performance.md``, lesson 11).
    """
    import sys
    if (needs_compile(dispatcher) if needed is None else needed) is not True:
        return False
    text = COMPILE_NOTICE if CACHE else COMPILE_NOTICE_NO_CACHE
    print(text.format(what, duration), file=sys.stderr if stream is None else stream,
          flush=True)
    return True


class PythonTwinCache(ContentFunctionCache):
    """:class:`ContentFunctionCache` of an internal kernel's twin
    (:class:`PythonTwinCacheImpl`)."""

    _impl_class = PythonTwinCacheImpl

