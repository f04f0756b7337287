"""Lua 5.3 built as ArduPilot builds it (32-bit numbers, its parser's limits), from lupa's sources.

ArduPilot embeds Lua 5.3.6 (``libraries/AP_Scripting/lua/src``) and builds it with
``LUA_32BITS`` (``Tools/ardupilotwaf/boards.py``): integers and floats of 32 bits. Its copy
also lowers two limits of the parser. lupa's source distribution carries the same Lua 5.3.6
(``third-party/lua53``) and the C of its ``lupa.lua53`` module; compiled together with
ArduPilot's changes they give a ``LuaRuntime`` whose Lua refuses what ArduPilot's refuses
and computes what ArduPilot's computes. The build (a few seconds of the C compiler) is
made once and kept in a cache directory.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType

# The ArduPilot sources these facts were read from (master, 2025-10-26).
ARDUPILOT_COMMIT = "2a929aeaf47cc8eec8ed4e9af2c57a3b0d5ffb0d"
LUA_VERSION = "5.3.6"  # lua.h of libraries/AP_Scripting/lua/src, and of lupa's lua53
DEFINES = ("LUA_32BITS",)  # Tools/ardupilotwaf/boards.py: env.DEFINES.update(LUA_32BITS = 1)


@dataclass(frozen=True)
class Limit:
    """A line of Lua's sources that ArduPilot's copy changes: where, stock and ArduPilot's."""

    name: str
    file: str
    stock: str
    ardupilot: str
    what: str


LIMITS = (
    Limit(
        "MAXVARS",
        "lparser.c",
        "#define MAXVARS\t\t200",
        "#define MAXVARS\t\t100",
        "local variables in scope at once in one function (the main chunk is one)",
    ),
    Limit(
        "MAXUPVAL",
        "lfunc.h",
        "#define MAXUPVAL\t255",
        "#define MAXUPVAL\t127",
        "upvalues of one function",
    ),
    Limit(
        "LUAL_BUFFERSIZE",
        "luaconf.h",
        "((int)(0x80 * sizeof(void*) * sizeof(lua_Integer)))",
        "((int)(0x20 * sizeof(void*) * sizeof(lua_Integer)))",
        "the C buffer that string building uses (not a limit a script meets)",
    ),
)
MAX_LOCALS = int(LIMITS[0].ardupilot.split()[-1])  # MAXVARS: more in one function is refused
RECIPE = "1"  # bump when the build below changes: cached builds are then made again

SdistFetcher = Callable[[str, Path], Path]
Say = Callable[[str], None]


class BuildError(Exception):
    """The interpreter cannot be built here (no compiler, no PyPI, an unexpected sdist)."""


def lupa_version() -> str:
    from importlib.metadata import version

    return version("lupa")


def default_cache() -> Path:
    """Where builds are kept: $XDG_CACHE_HOME (or ~/.cache)/gimbal-analyzer/ardupilot-lua."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
    return Path(base) / "gimbal-analyzer" / "ardupilot-lua"


def fetch_sdist(version: str, into: Path) -> Path:
    """lupa's source distribution from the package index, with pip (``pip download``).

    pip runs the sdist's setup.py for its metadata; LUPA_NO_LUAJIT spares it building
    LuaJIT (two minutes) for that."""
    into.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps"]
    command += ["--no-binary", "lupa", f"lupa=={version}", "-d", str(into)]
    env = {**os.environ, "LUPA_NO_LUAJIT": "true"}
    done = subprocess.run(
        command, capture_output=True, text=True, encoding="utf-8", check=False, env=env
    )
    found = sorted(into.glob(f"lupa-{version}.tar.gz"))
    if done.returncode != 0 or not found:
        why = (done.stderr or done.stdout).strip().splitlines()
        raise BuildError(f"pip could not download lupa {version}'s sources: {why[-1:] or '?'}")
    return found[0]


def build(
    cache_dir: Path | None = None,
    *,
    version: str | None = None,
    fetch: SdistFetcher = fetch_sdist,
    say: Say | None = None,
) -> Path:
    """The path of the built module (building it, and fetching lupa's sdist, if needed)."""
    root = cache_dir or default_cache()
    version = version or lupa_version()
    sdist = root / f"lupa-{version}.tar.gz"
    if not sdist.is_file():
        if say:
            say(f"downloading lupa {version}'s sources (once) into {root}")
        got = fetch(version, root / "download")
        os.replace(got, sdist)
    digest = hashlib.sha256(sdist.read_bytes()).hexdigest()[:16]
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    target = root / f"lua53-ardupilot-{version}-{digest}-r{RECIPE}{suffix}"
    if target.is_file():
        return target
    if say:
        say(f"building Lua {LUA_VERSION} as ArduPilot does (once) into {root}")
    with tempfile.TemporaryDirectory(dir=root) as work:
        sources = _unpack(sdist, Path(work))
        built = _compile(sources, Path(work) / f"out{suffix}")
        os.replace(built, target)
    return target


def _unpack(sdist: Path, work: Path) -> Path:
    """lupa's lua53.c and Lua's sources from the sdist, with ArduPilot's limits."""
    out = work / "src"
    out.mkdir()
    with tarfile.open(sdist) as tar:
        for member in tar.getmembers():
            parts = Path(member.name).parts
            wanted = parts[1:3] == ("third-party", "lua53") and len(parts) == 4
            wanted = wanted or parts[1:] == ("lupa", "lua53.c")
            if wanted and member.isfile() and member.name.endswith((".c", ".h")):
                data = tar.extractfile(member)
                assert data is not None
                (out / parts[-1]).write_bytes(data.read())
    for limit in LIMITS:
        path = out / limit.file
        if not path.is_file():
            raise BuildError(f"{sdist.name} has no third-party/lua53/{limit.file}")
        text = path.read_text(encoding="latin-1")
        if text.count(limit.stock) != 1:
            raise BuildError(f"{sdist.name}: {limit.file} has no '{limit.stock.strip()}'")
        path.write_text(text.replace(limit.stock, limit.ardupilot), encoding="latin-1")
    return out


def _compile(src: Path, target: Path) -> Path:
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise BuildError("no C compiler (cc or gcc) found: install gcc")
    include = sysconfig.get_paths()["include"]
    if not (Path(include) / "Python.h").is_file():
        raise BuildError(f"no Python.h in {include}: install Python's headers (python3-dev)")
    skip = {"lua.c", "luac.c", "ltests.c", "onelua.c", "lua53.c"}
    lua_sources = sorted(str(p) for p in src.glob("*.c") if p.name not in skip)
    command = [compiler, "-O2", "-shared", "-fPIC", "-std=gnu99", "-w"]
    command += [f"-D{name}" for name in DEFINES]
    command += ["-DCYTHON_CLINE_IN_TRACEBACK=0", f"-I{src}", f"-I{include}"]
    command += ["-o", str(target), str(src / "lua53.c"), *lua_sources, "-lm"]
    done = subprocess.run(command, capture_output=True, text=True, encoding="utf-8", check=False)
    if done.returncode != 0:
        raise BuildError(f"the C compiler failed: {done.stderr.strip()[-2000:]}")
    return target


@cache
def load(path: Path) -> ModuleType:
    """The built module (its ``LuaRuntime`` is lupa's, on ArduPilot's Lua)."""
    import lupa.lua53  # noqa: F401 - lupa's own first, so both live side by side

    name = "analyzer_ardupilot_lua.lua53"  # the last part names its PyInit_lua53
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    if spec is None:
        raise BuildError(f"cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module
