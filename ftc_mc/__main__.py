"""``python -m ftc_mc`` runs the command-line interface."""

from .cli import main

main()
