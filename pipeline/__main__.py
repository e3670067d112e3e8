"""``python -m rockmass`` runs the command-line interface."""

from rockmass.cli import main

raise SystemExit(main())
