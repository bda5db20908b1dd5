"""The entry point: an interrupt while the command line is still importing is one line and
status 130 (issue 29: a Ctrl-C in the first second printed a traceback from inside scipy)."""

from __future__ import annotations

import subprocess
import sys

#: A run of the entry point in which importing the command line is interrupted, as a Ctrl-C
#: landing during the import would (deterministic: an import hook raises it).
_INTERRUPTED_IMPORT = """
import sys
class Interrupt:
    def find_spec(self, name, path=None, target=None):
        if name == "meshladar.cli.commands":
            raise KeyboardInterrupt
        return None
sys.meta_path.insert(0, Interrupt())
from meshladar.__main__ import run
sys.exit(run(["materials"]))
"""


def test_an_interrupt_during_the_import_is_one_line():
    done = subprocess.run([sys.executable, "-c", _INTERRUPTED_IMPORT], capture_output=True,
                          text=True)
    assert done.returncode == 130
    assert done.stderr == "meshladar: interrupted\n"


def test_the_script_and_python_m_run_the_same_entry():
    import meshladar.__main__ as entry

    assert entry.run(["materials"]) == 0
    done = subprocess.run([sys.executable, "-m", "meshladar", "materials"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "dark_gray" in done.stdout


#: The script's end: an atexit handler would run in a normal interpreter teardown.
_TEARDOWN = """
import atexit, sys
atexit.register(print, "teardown ran")
from meshladar.__main__ import script
script(sys.argv[1:])
"""


def test_the_script_ends_without_the_interpreters_teardown(tmp_path):
    """The script's status and output are the command's (stdout flushed through a pipe, a
    file written), and the interpreter's teardown is skipped (an atexit handler does not
    run); a failing command keeps its status 2 and its one line."""
    out = tmp_path / "disk.npz"
    done = subprocess.run([sys.executable, "-c", _TEARDOWN, "simulate", "disk", "-o",
                           str(out)], capture_output=True, text=True)
    assert done.returncode == 0 and out.is_file(), done.stderr
    assert "teardown ran" not in done.stdout and done.stdout.strip()
    bad = subprocess.run([sys.executable, "-c", _TEARDOWN, "simulate", "missing.stl", "-o",
                          str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.startswith("meshladar: error:")
    assert "teardown ran" not in bad.stdout
