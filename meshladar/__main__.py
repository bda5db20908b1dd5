"""``python -m meshladar``: the command line."""

from .cli import main

raise SystemExit(main())
