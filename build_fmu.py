#!/usr/bin/env python
"""Build dist/ChainDrive.fmu (FMI 2.0 co-simulation) from fmu_src/ChainDrive.py with pythonfmu.

    python build_fmu.py                     # -> dist/ChainDrive.fmu, validated with fmpy
    python build_fmu.py --out some/dir/X.fmu
    python build_fmu.py --reference         # also regenerate docs/fmu_reference.csv (regression
                                            # reference produced by the FMU just built)
    python build_fmu.py --doc               # also rewrite the variable table in docs/fmu.md
    python build_fmu.py --warm 0,1,2,3      # compile these levels' kernels for this machine now
                                            # (default 0,1,2; --warm none skips)
    python build_fmu.py --default chain.link_stiffness=1.02e8 --out other.fmu
                                            # other parameter defaults (start values), e.g.
                                            # a user's own drive, or a perturbed build for tests
    python build_fmu.py --no-launcher       # pythonfmu's binary as ChainDrive.so (no launcher)
    python build_fmu.py --launch Motor.fmu  # only put the launcher in front of another
                                            # pythonfmu FMU's binary (in place, or --out)

Steps:
1. stage a copy of the ``chainmodel`` package as ``resources/_vendor/chainmodel`` and the
   adapter as ``resources/_vendor/ChainDrive.py`` (with its ``embedding.py``); their content hash is the build id
   (``resources/_vendor/build.json``, with the pythonfmu version). Inside a process the adapter is the module
   ``_chaindrive_<id>_adapter`` and the package ``_chaindrive_<id>``, and pythonfmu's entry
   module is ``resources/chaindrive_<id>.py`` (see SHIM), so any number of different builds
   coexist in one process and none touches the host's own ``chainmodel``;
2. let pythonfmu build the FMU (entry module, its own pythonfmu copy, the binaries,
   documentation/: docs/fmu.md as index.html, docs/fmu_reference.csv as ChainDrive_ref.csv and
   the regression references references/ as fmu_references/, which ``chainmodel fmu-test``
   uses); ``--default NAME=VALUE`` writes ``resources/_vendor/defaults.json``, which the
   adapter's parameters start from, and the same value as the start value in the XML;
   On Linux, with a C compiler (``$CC``, cc or gcc), ``binaries/linux64/ChainDrive.so`` is the
   launcher (``fmu_src/launcher/launcher.c``, compiled for the Python running this script, whose
   executable and libpython it records) and pythonfmu's binary ships beside it as
   ``ChainDrive.pythonfmu.so``: C/C++ hosts need no set-up (docs/fmu.md, "Hosts"). Without a
   compiler the build says so on stderr and ships pythonfmu's binary as ``ChainDrive.so``;
3. complete the modelDescription.xml pythonfmu writes: unit definitions with SI base units and
   display units, a unit on every Real, min/max of the parameters, explicit causality /
   variability / initial, output descriptions that say at which fidelity levels each output is
   a quasi-static estimate, ModelStructure Outputs and InitialUnknowns, DefaultExperiment and
   the capability flags (variable step, get/set and serialize state);
4. check the result with ``fmpy.validation.validate_fmu``; any problem fails the build;
5. warm the per-machine kernel cache (docs/numba_cache.md) for this build: a 1 ms run through
   the FMU at each level of ``--warm`` compiles the kernels the FMU will load, so the first
   simulation after a build does not pay the compile (the build does, once per machine and
   build; a rebuild of the same sources finds them cached and takes well under a second per
   level).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import html
import math
import re
import shutil
import sys
import tempfile
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # describe the chainmodel we vendor, not another installed one

ADAPTER = HERE / "fmu_src" / "ChainDrive.py"
DEFAULT_OUT = HERE / "dist" / "ChainDrive.fmu"
REFERENCE_CSV = HERE / "docs" / "fmu_reference.csv"
REFERENCES = HERE / "references"
DOC_MD = HERE / "docs" / "fmu.md"

# what the modelDescription completion needs: chainmodel.fmu_model_description (tested there)
from chainmodel.fmu_model_description import (BASE, CAPABILITIES, DISPLAY, SPEED_DISPLAY,  # noqa: E402,F401
                                              DescriptionError, base_unit, fmt, library_metadata)
from chainmodel.fmu_model_description import complete_model_description as _complete  # noqa: E402


def absolute_self_references(package: Path) -> list[str]:
    """Places where the package names itself absolutely ('from chainmodel.x import', or
    resources.files / import_module with 'chainmodel...'). Inside the FMU the vendored copy has
    a private name, so such a reference reaches the host's chainmodel (or fails) instead."""
    import ast
    found = []
    for path in sorted(package.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            name = None
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                name = node.module
            elif isinstance(node, ast.Import):
                name = next((a.name for a in node.names if a.name.split(".")[0] == "chainmodel"), None)
            elif (isinstance(node, ast.Call) and node.args
                  and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
                  and getattr(node.func, "attr", getattr(node.func, "id", "")) in ("files", "import_module")):
                name = node.args[0].value
            if name and name.split(".")[0] == "chainmodel":
                found.append(f"{path.relative_to(package.parent)}:{node.lineno} ({name})")
    return found


# --- modelDescription.xml --------------------------------------------------------------------

def model_structure_dependencies() -> dict[str, list[str]]:
    """Each output's direct input dependencies for ModelStructure
    (``chainmodel.fmu_model_description.output_dependencies``: found by perturbing the library's
    session at every level), computed in a subprocess with the plain-numpy kernels
    (CHAINMODEL_NUMBA=0; the same table as compiled, 1 s instead of compiling level 3 here)."""
    import os
    import subprocess
    code = ("import json; from chainmodel.fmu_model_description import output_dependencies; "
            "print(json.dumps(output_dependencies()))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=HERE,
                          env=dict(os.environ, CHAINMODEL_NUMBA="0"))
    if proc.returncode != 0:
        raise SystemExit("build_fmu: cannot find the outputs' input dependencies:\n"
                         + proc.stderr[-3000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def complete_model_description(xml: bytes, meta: dict) -> bytes:
    """Add what pythonfmu does not write (chainmodel.fmu_model_description)."""
    try:
        return _complete(xml, meta)
    except DescriptionError as exc:
        raise SystemExit(f"build_fmu: {exc}") from None


# --- documentation ---------------------------------------------------------------------------

def markdown_to_html(text: str, title: str) -> str:
    """Enough Markdown for docs/fmu.md: headings, paragraphs, lists, tables, code blocks."""
    out, para, in_code, in_list, table = [], [], False, False, []

    def inline(s):
        s = html.escape(s)
        s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
        s = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", s)
        return re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', s)

    def flush():
        nonlocal para, in_list, table
        if para:
            out.append("<p>" + inline(" ".join(para)) + "</p>")
            para = []
        if in_list:
            out.append("</ul>")
            in_list = False
        if table:
            rows = [r for r in table if not re.fullmatch(r"\|[\s:|-]+\|?", r)]
            cells = [[c.strip() for c in r.strip().strip("|").split("|")] for r in rows]
            out.append("<table>")
            for i, row in enumerate(cells):
                tag = "th" if i == 0 else "td"
                out.append("<tr>" + "".join(f"<{tag}>{inline(c)}</{tag}>" for c in row) + "</tr>")
            out.append("</table>")
            table = []

    for line in text.splitlines():
        if line.startswith("<!--"):
            continue
        if line.startswith("```"):
            flush()
            out.append("</pre>" if in_code else "<pre>")
            in_code = not in_code
        elif in_code:
            out.append(html.escape(line))
        elif line.startswith("#"):
            flush()
            level = len(line) - len(line.lstrip("#"))
            out.append(f"<h{level}>{inline(line[level:].strip())}</h{level}>")
        elif line.startswith("|"):
            if para:
                flush()
            table.append(line)
        elif re.match(r"\s*[-*] ", line):
            if para or table:
                flush()
            if not in_list:
                out.append("<ul>")
                in_list = True
            out.append("<li>" + inline(re.sub(r"^\s*[-*] ", "", line)) + "</li>")
        elif not line.strip():
            flush()
        else:
            if table:
                flush()
            para.append(line.strip())
    flush()
    body = "\n".join(out)
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(title)}"
            "</title><style>body{font-family:sans-serif;max-width:60em;margin:auto}"
            "table{border-collapse:collapse}td,th{border:1px solid #aaa;padding:2px 6px}"
            "pre{background:#f4f4f4;padding:6px}</style></head><body>\n"
            f"{body}\n</body></html>\n")


def stage_documentation(dest: Path) -> None:
    dest.mkdir(parents=True)
    text = DOC_MD.read_text() if DOC_MD.is_file() else (
        "# ChainDrive FMU\n\nSee docs/fmu.md in the ChainDrive repository.\n")
    (dest / "index.html").write_text(markdown_to_html(text, "ChainDrive FMU"))
    if REFERENCE_CSV.is_file():
        shutil.copy2(REFERENCE_CSV, dest / "ChainDrive_ref.csv")
    if REFERENCES.is_dir():   # the regression references (chainmodel fmu-test), Cross-Check layout
        shutil.copytree(REFERENCES, dest / "fmu_references",
                        ignore=shutil.ignore_patterns(".*", "__pycache__"))


# --- build -----------------------------------------------------------------------------------

def build_id(vendor: Path) -> str:
    """Content hash of what runs inside the FMU: the adapter, the vendored package (every file,
    by relative path) and the pythonfmu version whose wrapper binary is shipped. Two builds that
    differ anywhere get different module names; rebuilding the same sources gives the same id."""
    import pythonfmu
    h = hashlib.sha256(f"pythonfmu {pythonfmu.__version__}".encode())
    for path in sorted(p for p in vendor.rglob("*") if p.is_file()):
        h.update(b"\0" + path.relative_to(vendor).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:16]


#: the module pythonfmu loads (resources/<name>.py, named in slavemodule.txt). pythonfmu 0.7
#: imports it by name once per process and then re-executes this file's code in the module's
#: namespace at EVERY fmi2Instantiate to find the slave class (PySlaveInstance.cpp, findClass).
#: So the file only binds the class, which is loaded once per process under a name unique to
#: the build: nothing is redefined (no new class object leaks per instance) and two builds never
#: see each other's code. findClass also releases a reference to the module's namespace it
#: never took (Py_DECREF of PyModule_GetDict's borrowed dict); the last line gives it one.
SHIM = '''"""Entry point of ChainDrive.fmu build {build_id}, generated by build_fmu.py: binds the slave
class for pythonfmu, see build_fmu.SHIM."""
import sys as _sys
if "{adapter}" not in _sys.modules:
    import importlib.util as _util
    import os as _os
    _spec = _util.spec_from_file_location(
        "{adapter}", _os.path.join(_os.path.dirname(_os.path.abspath(__file__)), "_vendor",
                                   "ChainDrive.py"))
    _module = _util.module_from_spec(_spec)
    _sys.modules["{adapter}"] = _module
    try:
        _spec.loader.exec_module(_module)
    except BaseException:
        del _sys.modules["{adapter}"]
        raise
ChainDrive = _sys.modules["{adapter}"].ChainDrive
_sys.modules["{adapter}"].balance_namespace_reference(globals())
'''


# --- the launcher: ChainDrive.so for C/C++ hosts (fmu_src/launcher/launcher.c) ------------------

LAUNCHER_SRC = HERE / "fmu_src" / "launcher"


def backend_file(model_identifier: str) -> str:
    """Name under which pythonfmu's binary is shipped beside the launcher."""
    return f"{model_identifier}.pythonfmu.so"


def recorded_libpython() -> str:
    """The shared libpython of the Python running the build ('' for a static one): LIBDIR/
    INSTSONAME, or under LIBDIR/MULTIARCH as Debian installs it (the launcher asks a python
    named by CHAINDRIVE_PYTHON the same way)."""
    import os
    import sysconfig
    d, n, m = (sysconfig.get_config_var(k) or "" for k in ("LIBDIR", "INSTSONAME", "MULTIARCH"))
    candidates = [os.path.join(d, n), os.path.join(d, m, n)] if n else []
    return next((c for c in candidates if os.path.isfile(c)), "")


def c_string(text: str) -> str:
    """C string literal of ``text`` (UTF-8; anything but plain path characters as octal)."""
    plain = set(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/._-+:=@ ,")
    return '"' + "".join(chr(b) if b in plain else f"\\{b:03o}" for b in text.encode()) + '"'


def compile_launcher(model_identifier: str, dest: Path, quiet: bool = False) -> Path | None:
    """Compile the launcher for this machine's Python into ``dest``/<model_identifier>.so, or say
    on stderr why not and return None (the FMU then ships pythonfmu's binary as before)."""
    import os
    import subprocess
    if not sys.platform.startswith("linux"):
        return None
    cc = next((c for c in (os.environ.get("CC"), "cc", "gcc") if c and shutil.which(c)), None)
    if cc is None:
        print("build_fmu: no C compiler found (cc, gcc, $CC): the FMU ships pythonfmu's binary "
              "as ChainDrive.so; C/C++ hosts then need the LD_PRELOAD/PYTHONHOME/PYTHONPATH "
              "recipe of docs/fmu.md (Hosts)", file=sys.stderr)
        return None
    python = os.path.abspath(sys.executable)
    libpython = recorded_libpython()
    if not libpython and not quiet:
        print(f"build_fmu: {python} has no shared libpython: C/C++ hosts will need "
              "CHAINDRIVE_PYTHON (docs/fmu.md, Hosts)", file=sys.stderr)
    dest.mkdir(parents=True, exist_ok=True)
    (dest / "launcher_config.h").write_text(
        "/* generated by build_fmu.py */\n"
        f"#define RECORDED_PYTHON {c_string(python)}\n"
        f"#define RECORDED_LIBPYTHON {c_string(libpython)}\n"
        f"#define BACKEND_FILE {c_string(backend_file(model_identifier))}\n"
        f"#define FMU_NAME {c_string(model_identifier + ' FMU')}\n")
    out = dest / f"{model_identifier}.so"
    cmd = [cc, "-shared", "-fPIC", "-O2", "-Wall", "-I", str(dest), "-I", str(LAUNCHER_SRC),
           "-o", str(out), str(LAUNCHER_SRC / "launcher.c"), "-ldl", "-lpthread",
           "-Wl,-z,nodelete"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        print(f"build_fmu: compiling the launcher failed ({' '.join(cmd)}):\n{proc.stderr}"
              "the FMU ships pythonfmu's binary as ChainDrive.so; C/C++ hosts then need the "
              "recipe of docs/fmu.md (Hosts)", file=sys.stderr)
        return None
    return out


def launch_fmu(fmu: Path, out: Path) -> Path:
    """Put the launcher in front of the Linux binary of any pythonfmu FMU (``fmu``), writing
    ``out``: C/C++ hosts then run it without configuration and its process exits cleanly
    (docs/fmu.md, Hosts). The FMU is otherwise copied unchanged."""
    fmu, out = Path(fmu).resolve(), Path(out).resolve()
    with zipfile.ZipFile(fmu) as src:
        root = ET.fromstring(src.read("modelDescription.xml"))
        cosim = root.find("CoSimulation")
        if cosim is None:
            raise ValueError(f"{fmu}: not a co-simulation FMU (no CoSimulation element)")
        mid = cosim.get("modelIdentifier")
        names = src.namelist()
        wrapper = f"binaries/linux64/{mid}.so"
        if wrapper not in names:
            raise ValueError(f"{fmu}: has no {wrapper}")
        if f"binaries/linux64/{backend_file(mid)}" in names:
            raise ValueError(f"{fmu}: already has a launcher ({backend_file(mid)})")
        if "resources/slavemodule.txt" not in names:
            raise ValueError(f"{fmu}: not a pythonfmu FMU (no resources/slavemodule.txt)")
        with tempfile.TemporaryDirectory(prefix="launch_") as tmp:
            binary = compile_launcher(mid, Path(tmp))
            if binary is None:
                raise RuntimeError("no launcher could be compiled (see the message above)")
            out.parent.mkdir(parents=True, exist_ok=True)
            partial = out.with_name(out.name + ".part")
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as dst:
                for info in src.infolist():
                    data = src.read(info.filename)
                    if info.filename == wrapper:
                        dst.writestr(f"binaries/linux64/{backend_file(mid)}", data)
                        data = binary.read_bytes()
                    dst.writestr(info.filename, data)
            partial.replace(out)
    return out


def build(out: Path = DEFAULT_OUT, quiet: bool = False,
          defaults: dict | None = None, launcher: bool = True) -> Path:
    """Build, complete and validate the FMU at ``out``; return its path. ``defaults``: parameter
    name -> value replacing the library's default in this build (the start value in
    modelDescription.xml and the value an instance starts with; ``_vendor/defaults.json``)."""
    from pythonfmu import FmuBuilder

    out = Path(out).resolve()
    meta = library_metadata()
    meta["dependencies"] = model_structure_dependencies()
    defaults = dict(defaults or {})
    if defaults:
        from chainmodel import parameters as P
        P.validate(defaults)      # ValueError naming the parameter, the value, the valid range
        meta["defaults"] = {k: P.BY_NAME[k].kind(v) for k, v in defaults.items()}
    with tempfile.TemporaryDirectory(prefix="chaindrive_build_") as tmp:
        tmp = Path(tmp)
        vendor = tmp / "stage" / "_vendor"
        shutil.copytree(HERE / "chainmodel", vendor / "chainmodel",
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo"))
        shutil.copy2(ADAPTER, vendor / "ChainDrive.py")
        shutil.copy2(ADAPTER.with_name("embedding.py"), vendor / "embedding.py")
        if defaults:
            (vendor / "defaults.json").write_text(json.dumps(meta["defaults"], sort_keys=True))
        bid = build_id(vendor)
        import pythonfmu
        (vendor / "build.json").write_text(json.dumps({"id": bid,
                                                       "pythonfmu": pythonfmu.__version__}))
        shim = tmp / "stage" / f"chaindrive_{bid}.py"
        shim.write_text(SHIM.format(build_id=bid, adapter=f"_chaindrive_{bid}_adapter"))
        stage_documentation(tmp / "documentation")
        refs = absolute_self_references(vendor / "chainmodel")
        if refs and not quiet:
            print("note: absolute self-references in chainmodel; inside the FMU they do not reach "
                  "its own copy (use relative imports / __package__):\n  " + "\n  ".join(refs),
                  file=sys.stderr)
        raw = FmuBuilder.build_FMU(shim, dest=tmp / "raw", project_files=[vendor],
                                   documentation_folder=tmp / "documentation",
                                   canGetAndSetFMUstate=True, canSerializeFMUstate=True)
        out.parent.mkdir(parents=True, exist_ok=True)
        wrapper = "binaries/linux64/ChainDrive.so"
        binary = compile_launcher("ChainDrive", tmp / "launcher", quiet) if launcher else None
        with zipfile.ZipFile(raw) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
            for info in src.infolist():
                data = src.read(info.filename)
                if info.filename == "modelDescription.xml":
                    data = complete_model_description(data, meta)
                if info.filename == wrapper and binary is not None:   # launcher in front
                    dst.writestr(wrapper.replace("ChainDrive.so", backend_file("ChainDrive")),
                                 data)
                    data = binary.read_bytes()
                dst.writestr(info.filename, data)
    from fmpy.validation import validate_fmu
    problems = validate_fmu(str(out))
    if problems:
        raise SystemExit("build_fmu: the FMU does not validate:\n  " + "\n  ".join(problems))
    if not quiet:
        print(f"wrote {out} (fidelity levels {', '.join(map(str, meta['levels']))}; "
              "fmpy validation: no problem)")
    return out


def write_reference(fmu: Path, path: Path = REFERENCE_CSV) -> Path:
    """Regression reference: the xu2010 scene at fidelity 0 for 0.2 s, run through the FMU."""
    from chainmodel.fmu import simulate_fmu, reference_scene
    result = simulate_fmu(fmu, reference_scene())
    result.to_csv(path)
    print(f"wrote {path} ({len(result.time)} samples)")
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="FMU file to write")
    ap.add_argument("--reference", action="store_true",
                    help="regenerate docs/fmu_reference.csv with the FMU just built")
    ap.add_argument("--doc", action="store_true",
                    help="rewrite the generated variable table in docs/fmu.md")
    ap.add_argument("--default", action="append", default=[], metavar="NAME=VALUE",
                    help="build with another default (start value) of a parameter; repeatable")
    ap.add_argument("--warm", default="0,1,2", metavar="LEVELS",
                    help="fidelity levels whose compiled kernels to cache for this machine after "
                         "the build, comma-separated (default 0,1,2; 'none' skips)")
    ap.add_argument("--no-launcher", dest="launcher", action="store_false",
                    help="ship pythonfmu's binary as ChainDrive.so, without the launcher that "
                         "starts Python in C/C++ hosts (docs/fmu.md, Hosts)")
    ap.add_argument("--launch", type=Path, metavar="FMU",
                    help="only put the launcher in front of another pythonfmu FMU's binary "
                         "(written to --out, default: FMU itself) and exit")
    ap.add_argument("-q", "--quiet", action="store_true")
    args = ap.parse_args(argv)
    if args.launch is not None:
        target = args.out if "--out" in (argv if argv is not None else sys.argv) else args.launch
        try:
            print(f"wrote {launch_fmu(args.launch, target)}")
        except (OSError, ValueError, RuntimeError, zipfile.BadZipFile) as exc:
            ap.error(f"--launch: {exc}")
        return 0
    from chainmodel.parameters import parse_text
    levels = parse_levels(ap, args.warm)
    defaults = {}
    for item in args.default:
        name, sep, value = item.partition("=")
        if not sep:
            ap.error(f"--default {item!r}: write NAME=VALUE")
        defaults[name.strip()] = parse_text(value)
    try:
        fmu = build(args.out, quiet=args.quiet, defaults=defaults, launcher=args.launcher)
    except ValueError as exc:
        ap.error(f"--default: {exc}")
    if args.doc:
        from chainmodel.fmu import update_doc_table
        update_doc_table(fmu, DOC_MD)
        print(f"updated the variable table in {DOC_MD}")
    if args.reference:
        write_reference(fmu)
    if args.doc or args.reference:   # ship the new documentation / reference in the FMU too
        build(args.out, quiet=True, defaults=defaults, launcher=args.launcher)
    warm(fmu, levels, quiet=args.quiet)
    return 0


def parse_levels(ap, text: str) -> tuple[int, ...]:
    """--warm's comma-separated fidelity levels ('none': no level)."""
    if text.strip().lower() in ("none", ""):
        return ()
    try:
        levels = tuple(sorted({int(v) for v in text.split(",")}))
    except ValueError:
        levels = (-1,)
    if any(v not in (0, 1, 2, 3) for v in levels):
        ap.error(f"--warm must list fidelity levels from 0, 1, 2, 3 (comma-separated) or "
                 f"'none', got {text!r}")
    return levels


def warm(fmu: Path, levels, quiet: bool = False) -> None:
    """Run 1 ms of the default scene through the FMU at each of ``levels`` (fmpy), so that the
    kernels this build loads are compiled into the per-machine cache now."""
    import time
    from chainmodel.fmu import FMUSession
    from chainmodel.scene import load_scene
    if not levels:
        return
    wall = time.perf_counter()
    with FMUSession(fmu) as session:
        for level in levels:
            session.run(load_scene("xu2010", fidelity=level, duration=1e-3))
    if 2 in levels:     # level 2's span-modes check calls level 0's split from Python, later
        load_scene("xu2010", fidelity=0).model().quasi_static_spans(0.0)
    if not quiet:
        print(f"compiled kernels of levels {', '.join(map(str, levels))} cached for this machine "
              f"({time.perf_counter() - wall:.1f} s)")


if __name__ == "__main__":
    sys.exit(main())
