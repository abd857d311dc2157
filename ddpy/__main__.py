"""Allow ``python -m ddpy``."""

from ddpy.app.cli import main

raise SystemExit(main())
