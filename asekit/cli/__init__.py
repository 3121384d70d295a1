"""The command line: ``python -m asekit reproduce | analyse | sweep`` and the static site."""
