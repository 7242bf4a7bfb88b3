"""``python -m strug_manip`` is the ``strug`` command."""

from strug_manip.cli import main

raise SystemExit(main())
