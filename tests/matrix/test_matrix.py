"""Bad input and faults to zero (issue 12): a matrix of bad calls and bad command lines.

The cases are data (``_matrix.py``: the :class:`Case` record and its registration; the
cases by area in ``_cases_values.py``, ``_cases_engine.py`` and ``_cases_cli.py``); this
module runs them. Each case is a call of the public API (kind "api") or a command line run
in this process through ``meshladar.cli.main`` (kind "cli"), and what must happen to it:

- ``error``: refused with one clear error;
- ``warn``: accepted, with a MeshladarWarning;
- ``ok``: a valid edge input that must just work (its value checked where that is cheap).

:func:`run_case` classifies what did happen:

- ``clear``: api: a MeshladarError (ParameterError, GeometryError, PhantomSpecError,
  MaterialFileError, RunFolderError, ResultFileError: each also a builtin such as
  ValueError) whose message is one line naming the argument or file (one of the case's
  ``names``); cli: exit status 2 and one line on stderr (after argparse's usage lines, if
  any) starting ``meshladar...: error:``, naming the option or file, and no traceback;
- ``vague``: such an error, but its message is more than one line or names none of them;
- ``traceback``: api: any other exception (numpy's IndexError, TypeError, AttributeError,
  RecursionError, MemoryError, zlib.error...); cli: an exception out of ``main``, exit
  status 1 (meshladar's "internal error"), any other status, or a traceback on stderr;
- ``warned``: returned, and a MeshladarWarning was emitted;
- ``accepted``: returned without one;
- ``wrong``: returned, but the case's value check failed (or the case wrote a file beside
  its folder, as an output named after the folder);
- ``late``: the work started before the bad input was refused (the case names the
  functions it must not reach: the paper's and the studies' simulations, the benchmarks);
- ``hang``: only in the report below, which runs each case in a child process with a
  timeout (the tests themselves have no deadline).

An error case must come out ``clear``, a warn case ``warned``, an ok case ``accepted``.
An error or warn case that comes out ``accepted`` is silent nonsense.

Every case runs with the address space capped a few GiB above what the process already
uses, so an allocation the code should have refused is a MemoryError (a "traceback"), never
a machine out of memory; a case that could fork without bound runs only after a cheap check
that the code still refuses it.

Report::

    python tests/matrix/test_matrix.py --report [--before PATH] [--json FILE] [--only SUBSTRING]

runs every case in its own process (120 s timeout, 6 GiB address space) and prints the
counts per outcome and every mismatch. ``--before PATH`` (or the environment variable
MESHLADAR_MATRIX_BEFORE) puts PATH first on sys.path, to run the same matrix against an
older checkout; there, a case that fails because a name did not exist yet (``module
'meshladar' has no attribute ...``) is counted as ``n/a``.
"""

from __future__ import annotations

import contextlib
import glob
import inspect
import io
import json
import os
import re
import sys
import warnings
from pathlib import Path

if __name__ == "__main__" and "--before" in sys.argv:    # before _matrix imports meshladar
    os.environ["MESHLADAR_MATRIX_BEFORE"] = os.path.abspath(
        sys.argv[sys.argv.index("--before") + 1])

import pytest  # noqa: E402

# the cases register themselves into CASES on import, in this order
import _cases_values  # noqa: E402, F401
import _cases_engine  # noqa: E402, F401
import _cases_cli  # noqa: E402, F401
import _cases_scan  # noqa: E402, F401
from _matrix import _BEFORE, CASES, ml  # noqa: E402

_dups = sorted({c.id for c in CASES if sum(d.id == c.id for d in CASES) > 1})
assert not _dups, f"case ids must be unique: {_dups}"

#: What each expectation requires of the outcome.
EXPECTED = {"error": "clear", "warn": "warned", "ok": "accepted"}
#: Address space a case may add to what the process already uses.
GUARD_BYTES = 4 * 2**30


# ================================================================== running a case

def _takes_tmp(call):
    try:
        return "tmp" in inspect.signature(call).parameters
    except (TypeError, ValueError):
        return False


def _vm_size():
    """This process's address space in bytes (Linux), or None."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


@contextlib.contextmanager
def memory_guard(headroom=GUARD_BYTES):
    """Cap the address space at what is in use plus ``headroom`` while a case runs: an
    allocation the code should have refused becomes a MemoryError, not an OOM."""
    try:
        import resource
    except ImportError:
        yield
        return
    used = _vm_size()
    if used is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = used + headroom
    for cap in (soft, hard):
        if cap != resource.RLIM_INFINITY:
            limit = min(limit, cap)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _meshladar_warning():
    return getattr(getattr(ml, "errors", None), "MeshladarWarning", Warning)


def _meshladar_error():
    return getattr(getattr(ml, "errors", None), "MeshladarError", ())


def _first_line(text):
    text = str(text).strip()
    return text.splitlines()[0] if text else ""


def _judge_error(case, message):
    """clear or vague, for an error meshladar raised on purpose."""
    one_line = "\n" not in message.strip()
    named = any(n in message for n in case.names) if case.names else True
    return ("clear" if one_line and named else "vague"), message


def _judge_return(case, value, caught):
    warned = [w for w in caught if issubclass(w.category, _meshladar_warning())]
    outcome = "warned" if warned else "accepted"
    message = _first_line(warned[0].message) if warned else ""
    if case.check is not None and case.expect != "error":
        try:
            good = bool(case.check(value))
        except Exception as exc:  # noqa: BLE001 - a failed check is a wrong value
            good, message = False, f"check raised {type(exc).__name__}: {exc}"
        if not good:
            return "wrong", message or f"value check failed: {_first_line(repr(value))[:160]}"
    return outcome, message


def _run_api(case, tmp):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            value = case.call(tmp) if _takes_tmp(case.call) else case.call()
        except _meshladar_error() as exc:
            return _judge_error(case, str(exc))
        except Exception as exc:  # noqa: BLE001 - anything else is a traceback to the user
            return "traceback", f"{type(exc).__name__}: {exc}"
    return _judge_return(case, value, caught)


_ERROR_LINE = re.compile(r"^meshladar( [\w-]+)*: error: ")


def _run_cli(case, tmp):
    from meshladar import cli as cli_module

    argv = [a.replace("{tmp}", str(tmp)) for a in case.call]
    out, err = io.StringIO(), io.StringIO()
    formatwarning = warnings.formatwarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = cli_module.main(argv)
                except SystemExit as exc:                 # argparse: --help, usage errors
                    code = 0 if exc.code is None else exc.code
        except Exception as exc:  # noqa: BLE001 - escaped main()
            return "traceback", f"{type(exc).__name__} escaped main(): {exc}"
        finally:
            warnings.formatwarning = formatwarning
    text = err.getvalue()
    lines = text.strip("\n").splitlines()
    if "Traceback" in text:
        return "traceback", text.strip()[-300:]
    if code == 0:
        return _judge_return(case, tmp, caught)
    if code == 1:
        return "traceback", _internal_error(text)
    if code != 2:
        return "traceback", f"exit status {code!r}: {_first_line(text)}"
    if not lines:
        return "vague", "exit status 2 and nothing on stderr"
    last = lines[-1]
    usage_only = all(line.startswith("usage:") or line.startswith(" ") for line in lines[:-1])
    if not _ERROR_LINE.match(last) or (len(lines) > 1 and not usage_only):
        return "vague", " | ".join(lines)[:300]
    return _judge_error(case, last)


def _internal_error(text):
    """The CLI's one-line internal error, with the exception from the traceback file it
    names (the file is removed)."""
    line = _first_line(text)
    m = re.search(r"traceback in (\S+\.txt)", text)
    if m and os.path.exists(m.group(1)):
        with open(m.group(1), encoding="utf-8") as fh:
            tail = fh.read().strip().splitlines()
        os.remove(m.group(1))
        if tail:
            line += f" [{tail[-1]}]"
    return line


class WorkStarted(Exception):
    """Raised by a function a case must not reach (its bad input is refused before)."""


@contextlib.contextmanager
def forbidding(targets):
    """Replace each "module:function" by one raising WorkStarted, for the duration."""
    import importlib

    saved = []
    try:
        for target in targets:
            module_name, name = target.split(":")
            try:
                module = importlib.import_module(module_name)
                saved.append((module, name, getattr(module, name)))
            except (ImportError, AttributeError):
                if _BEFORE:                             # an older meshladar: nothing to guard
                    continue
                raise                                   # a guard that guards nothing is a defect

            def reached(*args, _target=target, **kwargs):
                raise WorkStarted(f"{_target} was called: the work started before the bad "
                                  "input was refused")
            setattr(module, name, reached)
        yield
    finally:
        for module, name, original in reversed(saved):
            setattr(module, name, original)


def run_case(case, tmp):
    """Run one case in folder ``tmp`` (also the working folder): (outcome, message)."""
    tmp = Path(tmp)
    if case.precheck is not None and not case.precheck():
        return "traceback", "not refused up front: the cheap pre-check failed, not run"
    beside = f"{glob.escape(tmp.name)}.*"          # "-o FOLDER" must not write FOLDER.png
    before = set(tmp.parent.glob(beside))
    with contextlib.chdir(tmp):
        if case.setup is not None:
            case.setup(tmp)
        with forbidding(case.forbid), memory_guard():
            outcome, message = (_run_api if case.kind == "api" else _run_cli)(case, tmp)
    stray = sorted(set(tmp.parent.glob(beside)) - before)
    for path in stray:
        path.unlink()
    if stray:
        return "wrong", f"wrote {', '.join(p.name for p in stray)} beside its folder"
    late = re.search(r"(\S+:\S+) was called: the work started before the bad input", message)
    if late:
        return "late", f"the work started before the bad input was refused ({late.group(1)})"
    return outcome, message


def test_the_guide_states_the_number_of_cases():
    # the guide's command-line page says how many cases the matrix has: this number
    page = Path(__file__).resolve().parents[2] / "docs" / "guide" / "command_line.md"
    stated = re.search(r"\(`tests/matrix/`, (\d+) cases", page.read_text(encoding="utf-8"))
    assert stated and int(stated.group(1)) == len(CASES) == 1314


# ================================================================== the test

@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case, tmp_path):
    if case.skip_root and hasattr(os, "geteuid") and os.geteuid() == 0:
        pytest.skip("root ignores file permissions")
    outcome, message = run_case(case, tmp_path)
    want = EXPECTED[case.expect]
    if outcome != want:
        pytest.fail(f"{case.id}: expected {case.expect} ({want}), got {outcome}: {message}",
                    pytrace=False)


# ================================================================== the report

#: Seconds a case may take in the report before it counts as a hang.
REPORT_TIMEOUT = 120
#: Address space of a report child.
REPORT_MEMORY = 6 * 2**30
_MARK = "@@matrix-result@@"
_MISSING_NAME = re.compile(r"(module 'meshladar[\w.]*' has no attribute|No module named "
                           r"'meshladar|cannot import name .* from 'meshladar|type object "
                           r"'\w+' has no attribute)")


def _child(case_id):
    """Run one case in this process (a report child) and print its result."""
    import resource
    import tempfile

    resource.setrlimit(resource.RLIMIT_AS, (REPORT_MEMORY, REPORT_MEMORY))
    case = next(c for c in CASES if c.id == case_id)
    with tempfile.TemporaryDirectory(prefix="matrix-") as tmp:
        if case.skip_root and os.geteuid() == 0:
            outcome, message = "skipped", "root ignores file permissions"
        else:
            try:
                outcome, message = run_case(case, tmp)
            except Exception as exc:  # noqa: BLE001 - the case's own setup failed
                outcome, message = "traceback", f"setup: {type(exc).__name__}: {exc}"
        if outcome == "traceback" and _MISSING_NAME.search(message):
            outcome = "n/a"
        for root, dirs, _ in os.walk(tmp):          # read-only folders, for the cleanup
            for d in dirs:
                os.chmod(os.path.join(root, d), 0o755)
    sys.stdout.write(f"\n{_MARK}{json.dumps({'outcome': outcome, 'message': message})}\n")
    sys.stdout.flush()


def _spawn(case, before):
    import signal
    import subprocess

    env = dict(os.environ)
    if before:
        env["MESHLADAR_MATRIX_BEFORE"] = os.path.abspath(before)
    proc = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", case.id],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=REPORT_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return "hang", f"no answer within {REPORT_TIMEOUT} s"
    for line in reversed(out.splitlines()):
        if line.startswith(_MARK):
            result = json.loads(line[len(_MARK):])
            return result["outcome"], result["message"]
    if proc.returncode < 0:
        return "traceback", f"killed by signal {-proc.returncode}"
    return "traceback", f"child exit {proc.returncode}: {_first_line(err[-500:])}"


def report(argv):
    import time
    from concurrent.futures import ThreadPoolExecutor

    before = argv[argv.index("--before") + 1] if "--before" in argv else _BEFORE
    only = argv[argv.index("--only") + 1] if "--only" in argv else ""
    cases = [c for c in CASES if only in c.id]
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max(1, min(2, os.cpu_count() or 1))) as pool:
        results = list(pool.map(lambda c: _spawn(c, before), cases))
    seconds = time.perf_counter() - t0
    counts = {}
    for outcome, _ in results:
        counts[outcome] = counts.get(outcome, 0) + 1
    print(f"meshladar {ml.__version__} from {os.path.dirname(ml.__file__)}: {len(cases)} cases "
          f"in {seconds:.0f} s")
    for outcome in ("clear", "vague", "traceback", "late", "warned", "accepted", "wrong",
                    "hang", "n/a", "skipped"):
        if outcome in counts:
            print(f"  {outcome:<10} {counts[outcome]:4d}")
    mismatches = [(c, o, m) for c, (o, m) in zip(cases, results)
                  if o not in (EXPECTED[c.expect], "skipped", "n/a")]
    nonsense = sum(1 for c, o, _ in mismatches if o == "accepted")
    print(f"\n{len(mismatches)} mismatches ({nonsense} silent nonsense):")
    for c, o, m in mismatches:
        print(f"  {c.id:<48} expected {c.expect:<5} got {o:<9} {_first_line(m)[:200]}")
    if "--json" in argv:
        with open(argv[argv.index("--json") + 1], "w", encoding="utf-8") as fh:
            json.dump([{"id": c.id, "expect": c.expect, "outcome": o, "message": m}
                       for c, (o, m) in zip(cases, results)], fh, indent=1)
    return 0


if __name__ == "__main__":
    if "--child" in sys.argv:
        _child(sys.argv[sys.argv.index("--child") + 1])
    elif "--report" in sys.argv:
        sys.exit(report(sys.argv))
    else:
        print(__doc__)
