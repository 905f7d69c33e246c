"""`python -m gearjax.cli`: the `gearjax` command."""

from . import main

raise SystemExit(main())
