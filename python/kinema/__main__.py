"""``python -m kinema`` runs the ``kinema`` command."""

from .cli import main

main()
