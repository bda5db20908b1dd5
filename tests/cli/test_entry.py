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
