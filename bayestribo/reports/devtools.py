"""Headless Chromium driven over its DevTools protocol, through a pipe: no network, no
package beyond the standard library.

:class:`Chromium` starts the browser with ``--remote-debugging-pipe`` (it reads
commands on file descriptor 3 and writes answers on 4, each a JSON message ended by a
NUL byte), opens one tab and lets a caller lay a page out as a reader's device would:
at a window width, for the screen or for print (``Emulation.setEmulatedMedia``),
evaluate JavaScript in it (``Runtime.evaluate``, which a page's Content-Security-Policy
does not restrict) and print it to PDF (``Page.printToPDF``)::

    with Chromium() as browser:
        browser.open(path, width=680, media="print")
        widths = browser.evaluate("[...document.tables].map(t => t.scrollWidth)")
        pdf = browser.print_pdf(paper_mm=(210, 297))

The network is switched off as for :mod:`bayestribo.reports.browser` (a proxy that
refuses every connection).
"""

from __future__ import annotations

import base64
import json
import os
import select
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from bayestribo.reports._errors import ReportError

__all__ = ["Chromium"]

_MM_PER_INCH = 25.4


class Chromium:
    """One headless Chromium with one tab, driven over the DevTools protocol.

    Parameters
    ----------
    executable : str, optional
        Chromium to use (default :func:`bayestribo.reports.browser.find_chromium`).
    timeout : float
        Longest time one command or one page load may take [s].

    Raises
    ------
    ReportError
        Without Chromium, or if it does not answer within ``timeout``.
    """

    def __init__(self, executable: str | None = None, *, timeout: float = 120.0) -> None:
        self.executable = executable
        self.timeout = float(timeout)
        self._proc: subprocess.Popen[bytes] | None = None
        self._profile: tempfile.TemporaryDirectory[str] | None = None
        self._buffer = b""
        self._events: list[dict[str, Any]] = []
        self._next_id = 0
        self._session: str | None = None

    # -- the pipe ------------------------------------------------------------------
    def __enter__(self) -> Chromium:
        from bayestribo.reports.browser import _FLAGS, _chromium

        exe = _chromium(self.executable)
        self._profile = tempfile.TemporaryDirectory(prefix="bayestribo-chromium-")
        to_browser, self._write = os.pipe()
        self._read, from_browser = os.pipe()

        def pipes_on_3_and_4() -> None:  # in the child, before exec
            a, b = os.dup(to_browser), os.dup(from_browser)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self._proc = subprocess.Popen(
            [
                exe,
                *_FLAGS,
                f"--user-data-dir={self._profile.name}",
                "--remote-debugging-pipe",
                "about:blank",
            ],
            preexec_fn=pipes_on_3_and_4,  # the pipes on fds 3 and 4, as Chromium reads them
            pass_fds=(3, 4),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_browser)
        os.close(from_browser)
        target = self.call("Target.createTarget", {"url": "about:blank"}, session=False)
        attached = self.call(
            "Target.attachToTarget", {"targetId": target["targetId"], "flatten": True}, False
        )
        self._session = attached["sessionId"]
        self.call("Page.enable")
        self.call("Runtime.enable")
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the browser (and its profile folder)."""
        if self._proc is not None:
            try:
                self._send("Browser.close", {}, session=False)
                self._proc.wait(timeout=10)
            except (OSError, subprocess.TimeoutExpired):
                self._proc.kill()
                self._proc.wait()
            for fd in (self._write, self._read):
                try:
                    os.close(fd)
                except OSError:
                    pass
            self._proc = None
        if self._profile is not None:
            self._profile.cleanup()
            self._profile = None

    def _send(self, method: str, params: dict[str, Any], session: bool = True) -> int:
        self._next_id += 1
        message: dict[str, Any] = {"id": self._next_id, "method": method, "params": params}
        if session and self._session:
            message["sessionId"] = self._session
        os.write(self._write, json.dumps(message).encode("utf-8") + b"\0")
        return self._next_id

    def _receive(self, deadline: float) -> dict[str, Any]:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([self._read], [], [], max(left, 0.0))
            if not ready:
                raise ReportError(f"Chromium did not answer within {self.timeout:.0f} s")
            chunk = os.read(self._read, 1 << 20)
            if not chunk:
                raise ReportError("Chromium closed its DevTools pipe (it stopped)")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def call(
        self, method: str, params: dict[str, Any] | None = None, session: bool = True
    ) -> dict[str, Any]:
        """Send one DevTools command and return its result.

        Raises
        ------
        ReportError
            If Chromium answers with an error, or not within the timeout.
        """
        wanted = self._send(method, params or {}, session)
        deadline = time.monotonic() + self.timeout
        while True:
            message = self._receive(deadline)
            if message.get("id") == wanted:
                if "error" in message:
                    raise ReportError(f"Chromium refused {method}: {message['error']}")
                return message.get("result", {})
            self._events.append(message)

    def _wait_for(self, event: str) -> dict[str, Any]:
        deadline = time.monotonic() + self.timeout
        while True:
            for i, message in enumerate(self._events):
                if message.get("method") == event:
                    del self._events[: i + 1]
                    return message.get("params", {})
            self._events.append(self._receive(deadline))

    # -- pages ---------------------------------------------------------------------
    def add_script_on_load(self, source: str) -> None:
        """Run ``source`` in every page this tab opens from now on, before the page's own
        content (a DevTools script: the page's policy does not apply to it)."""
        self.call("Page.addScriptToEvaluateOnNewDocument", {"source": source})

    def open(
        self,
        page: str | Path,
        *,
        width: int = 1280,
        height: int = 1000,
        media: str = "screen",
    ) -> None:
        """Open ``page`` (a file path or URL) laid out ``width`` CSS pixels wide, for
        ``media`` ("screen" or "print"), and wait until it has loaded.

        Raises
        ------
        ReportError
            If ``media`` is neither "screen" nor "print".
        """
        if media not in ("screen", "print"):
            raise ReportError(f"media: expected 'screen' or 'print', got {media!r}")
        url = str(page)
        if "://" not in url:
            url = Path(page).resolve().as_uri()
        self.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": int(width), "height": int(height), "deviceScaleFactor": 1, "mobile": False},
        )
        self.call("Emulation.setEmulatedMedia", {"media": media})
        self._events.clear()
        self.call("Page.navigate", {"url": url})
        self._wait_for("Page.loadEventFired")

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the open page (JSON-like values).

        Raises
        ------
        ReportError
            If the expression throws.
        """
        found = self.call(
            "Runtime.evaluate",
            {"expression": expression, "returnByValue": True, "awaitPromise": True},
        )
        if "exceptionDetails" in found:
            details = found["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise ReportError(f"the page's script failed: {text}")
        return found.get("result", {}).get("value")

    def print_pdf(self, *, paper_mm: tuple[float, float] = (210.0, 297.0)) -> bytes:
        """The open page printed to PDF on paper of ``paper_mm`` (width, height) [mm],
        with the margins its stylesheet's ``@page`` rule gives.

        Returns
        -------
        bytes
            The PDF.
        """
        width, height = (v / _MM_PER_INCH for v in paper_mm)
        found = self.call(
            "Page.printToPDF",
            {
                "paperWidth": width,
                "paperHeight": height,
                "printBackground": True,
                "preferCSSPageSize": False,
            },
        )
        return base64.b64decode(found["data"])
