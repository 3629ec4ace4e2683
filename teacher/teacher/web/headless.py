"""Open the web teacher's page in the system's Chromium, headless, through Playwright.

For the browser tests, the overhead benchmark and a screenshot from the command line:

    python -m teacher.web.headless http://127.0.0.1:8765/ --screenshot page.png --wait 5

Playwright drives Debian's ``chromium`` (``apt-get install chromium``; test.sh installs it):
it never downloads a browser of its own. The flags keep Chromium off the network (this machine
has none) and out of the sandbox it cannot have as root in a container.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import tempfile
import time
from collections.abc import Iterator, Sequence

CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--disable-dev-shm-usage",
                  # a page on this machine's own address must not go to a proxy from the
                  # environment (loopback is exempt by default, another address is not)
                  "--no-proxy-server"]


class NoChromium(RuntimeError):
    """Chromium or Playwright is missing; the message says what to install."""


def chromium_path() -> str:
    path = os.environ.get("SGIM_CHROMIUM") or shutil.which("chromium") or shutil.which(
        "chromium-browser")
    if not path:
        raise NoChromium("no chromium found: apt-get install chromium (./test.sh does it), "
                         "or set SGIM_CHROMIUM to a Chromium executable")
    return path


@contextlib.contextmanager
def browser_page(viewport: tuple[int, int] = (1100, 940),
                 flags: Sequence[str] = ()) -> Iterator[object]:
    """A Playwright page in a fresh headless Chromium profile, closed afterwards; ``flags``:
    more Chromium switches (e.g. --host-resolver-rules)."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise NoChromium("the playwright package is missing: ./bootstrap.sh installs it "
                         "(requirements.txt)") from None
    executable = chromium_path()
    with tempfile.TemporaryDirectory(prefix="sgim-chromium-") as profile, \
            sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            profile, executable_path=executable, headless=True,
            args=[*CHROMIUM_FLAGS, *flags],
            viewport={"width": viewport[0], "height": viewport[1]})
        try:
            page = context.pages[0] if context.pages else context.new_page()
            yield page
        finally:
            context.close()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("url", help="the page's address (with its ?token= if it has one)")
    p.add_argument("--screenshot", help="PNG file to write")
    p.add_argument("--wait", type=float, default=3.0, help="seconds to let the page draw")
    args = p.parse_args(argv)
    try:
        with browser_page() as page:
            page.goto(args.url)
            time.sleep(args.wait)
            if args.screenshot:
                page.screenshot(path=args.screenshot)
            print(page.evaluate("JSON.stringify(window.teacherStats)"))
    except NoChromium as error:
        print(f"headless: {error}")
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
