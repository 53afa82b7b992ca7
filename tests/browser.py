"""Open an HTML report in a real headless browser (Debian's chromium, driven by Playwright).

The reports are read by people in a browser; a string check of the HTML cannot see an image
that does not load or a page that throws. :func:`load_in_browser` loads a file as a reader
would (``file://``, relative image paths resolved by the browser) and returns what it saw.

Where the browser is missing the tests that need it skip, unless ``MUFUSION_REQUIRE_BROWSER``
is set (CI sets it and installs chromium), where a missing browser is a failure.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


@dataclass(frozen=True)
class PageCheck:
    """What the browser saw: each image's source and natural width (0: it did not load), the
    console's error messages, failed requests, and the page's title."""

    images: list[tuple[str, int]]
    console_errors: list[str]
    failed_requests: list[str]
    title: str

    @property
    def broken_images(self) -> list[str]:
        return [src for src, width in self.images if width == 0]


def chromium_path() -> str:
    """The system chromium's path; skips (or fails where the browser is required)."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    message = "no chromium on PATH (Debian: apt-get install chromium)"
    if os.environ.get("MUFUSION_REQUIRE_BROWSER"):
        pytest.fail(message)
    pytest.skip(message)


def load_in_browser(html: Path, screenshot: Path | None = None) -> PageCheck:
    """Load ``html`` in headless chromium, wait until the page and its images have loaded, and
    return what it saw; with ``screenshot``, save a full-page PNG there."""
    executable = chromium_path()
    if os.environ.get("MUFUSION_REQUIRE_BROWSER"):
        from playwright import sync_api
    else:
        sync_api = pytest.importorskip("playwright.sync_api")
    errors: list[str] = []
    failed: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 900})
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.on("requestfailed", lambda r: failed.append(r.url))
            page.goto(html.resolve().as_uri(), wait_until="load")
            images = page.evaluate(
                "Array.from(document.images).map(i => [i.getAttribute('src'), i.naturalWidth])"
            )
            if screenshot is not None:
                page.screenshot(path=str(screenshot), full_page=False)
            title = page.title()
        finally:
            browser.close()
    return PageCheck([(str(s), int(w)) for s, w in images], errors, failed, title)
