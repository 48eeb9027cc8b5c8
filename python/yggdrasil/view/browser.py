"""The viewer's page in headless Chromium (Debian's ``chromium``, driven by Playwright
without a browser download of its own), for the tests and the benchmark: open the page,
read the status line the viewer writes, note when each generation became visible (a page
hook: a ``MutationObserver`` on the status line), take screenshots."""
from __future__ import annotations

import os
import re
import shutil
import tempfile
import time
from contextlib import contextmanager
from typing import Callable, Dict, Iterator, Optional, Tuple

#: Chromium's flags on a machine without a GPU or a network (and as root).
CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]

STATUS = re.compile(r"generation (\d+) · (\d+) layers · (\d+) nodes")

# Records, per generation, the wall-clock time (ms since the epoch, sub-ms) at which the
# status line first named it: the viewer writes that line after the scene's changes.
_HOOK = r"""
window.__yggShown = {};
const seen = () => {
  const m = document.body && document.body.innerText.match(/generation (\d+) · \d+ layers · \d+ nodes/);
  if (m && !(m[1] in window.__yggShown)) window.__yggShown[m[1]] = performance.timeOrigin + performance.now();
};
new MutationObserver(seen).observe(document, {subtree: true, childList: true, characterData: true});
"""


def chromium_path() -> Optional[str]:
    """Debian's Chromium (``$YGG_CHROMIUM`` or ``chromium`` on the PATH), or ``None``."""
    return os.environ.get("YGG_CHROMIUM") or shutil.which("chromium")


class ViewerPage:
    """One open page of the viewer."""

    def __init__(self, page) -> None:
        self.page = page

    def goto(self, url: str) -> None:
        """Loads the viewer's page (returns once the document has loaded)."""
        self.page.goto(url)

    def status(self, timeout_ms: float = 30_000) -> Tuple[int, int, int]:
        """Waits for the status line and returns ``(generation, layers, nodes)``."""
        self.page.wait_for_function("/generation \\d+ · \\d+ layers/.test(document.body.innerText)", timeout=timeout_ms)
        m = STATUS.search(self.page.inner_text("body"))
        assert m is not None
        return int(m[1]), int(m[2]), int(m[3])

    def wait_generation(self, generation: int, timeout_ms: float = 30_000) -> float:
        """Waits until the page shows ``generation`` (or a later one); returns the wall
        time it did, in ns since the epoch."""
        self.page.wait_for_function(
            f"Object.keys(window.__yggShown).some(g => Number(g) >= {generation})", timeout=timeout_ms
        )
        shown: Dict[str, float] = self.page.evaluate("window.__yggShown")
        first = min(t for g, t in shown.items() if int(g) >= generation)
        return first * 1e6

    def dismiss_notices(self) -> None:
        """Closes the notices shown over the view (viser's "software WebGL" warning)."""
        buttons = self.page.locator(".mantine-Notification-closeButton")
        for _ in range(buttons.count()):
            buttons.first.click()

    def screenshot(self, path: str) -> None:
        """Saves a PNG of the page, after two frames have been drawn."""
        self.page.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        self.page.screenshot(path=path)

    def screenshot_until(self, path: str, shows: Callable[[str], bool], timeout_s: float = 30.0) -> bool:
        """Takes screenshots to ``path``, one per drawn frame, until ``shows(path)`` is
        true (viser fades new scene nodes in over a few frames) or ``timeout_s`` passes;
        returns whether it became true."""
        deadline = time.monotonic() + timeout_s
        while True:
            self.screenshot(path)
            if shows(path):
                return True
            if time.monotonic() > deadline:
                return False


@contextmanager
def open_viewer(url: Optional[str], width: int = 1280, height: int = 800) -> Iterator[ViewerPage]:
    """Opens ``url`` in headless Chromium with a fresh profile (a blank page if ``None``:
    call ``ViewerPage.goto``); closes both after."""
    from playwright.sync_api import sync_playwright

    exe = chromium_path()
    if exe is None:
        raise RuntimeError("no chromium: apt-get install chromium (or set YGG_CHROMIUM)")
    profile = tempfile.mkdtemp(prefix="ygg-chromium-")
    try:
        with sync_playwright() as p:
            context = p.chromium.launch_persistent_context(
                profile, executable_path=exe, headless=True, args=CHROMIUM_ARGS,
                viewport={"width": width, "height": height},
            )
            try:
                page = context.new_page()
                page.add_init_script(_HOOK)
                viewer_page = ViewerPage(page)
                if url is not None:
                    viewer_page.goto(url)
                yield viewer_page
            finally:
                context.close()
    finally:
        shutil.rmtree(profile, ignore_errors=True)


def color_pixels(png_path: str, color: Tuple[int, int, int], tolerance: int = 12,
                 region: Optional[Tuple[int, int, int, int]] = None):
    """The ``(x, y)`` pixels of a PNG within ``tolerance`` of ``color`` (per channel),
    inside ``region`` ``(x0, y0, x1, y1)`` if given, as an ``(n, 2)`` array."""
    import imageio.v3 as iio
    import numpy as np

    img = iio.imread(png_path)[..., :3].astype(np.int16)
    mask = (np.abs(img - np.array(color, np.int16)) <= tolerance).all(axis=-1)
    if region is not None:
        x0, y0, x1, y1 = region
        keep = np.zeros_like(mask)
        keep[y0:y1, x0:x1] = True
        mask &= keep
    ys, xs = np.nonzero(mask)
    return np.stack([xs, ys], axis=1)
