"""``python -m fuzzygait`` runs the command line."""

from fuzzygait.cli import main

main()
