"""``python -m signorini``: the command line (``signorini.cli``)."""

from signorini.cli import main

raise SystemExit(main())
