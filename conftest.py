"""Test-collection settings shared by tests/ and the doctests in src/."""

from __future__ import annotations

import pytest

# ``python -m mufusion`` runs the CLI when imported: not a module for doctests.
collect_ignore = ["src/mufusion/__main__.py"]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the tests marked ``slow`` first, keeping the collection's order otherwise.

    With parallel workers (README's ``-n auto``; pyproject distributes whole files, in this order)
    the long files start at once and the short ones fill the workers' ends, instead of a long file
    starting last and running alone while the other worker idles.
    """
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
