"""``python -m bsv.bench ...``: the same as ``bsv bench ...``."""

from .main import main

raise SystemExit(main())
