"""Allow ``python -m ddpy``."""

from ddpy.cli import main

raise SystemExit(main())
