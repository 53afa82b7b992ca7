"""Test-collection settings shared by tests/ and the doctests in src/."""

# ``python -m mufusion`` runs the CLI when imported: not a module for doctests.
collect_ignore = ["src/mufusion/__main__.py"]
