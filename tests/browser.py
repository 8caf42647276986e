"""A tiny Chrome DevTools Protocol client over ``--remote-debugging-pipe`` (no port, no extra package):
load a page from disk in headless Chromium, collect console errors, evaluate, take a screenshot."""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


class Browser:
    def __init__(self):
        if not Path(CHROMIUM).is_file():
            raise RuntimeError("chromium is not installed: the browser tests need it (apt-get install chromium)")
        r1, self._w = os.pipe()  # we write → chromium reads on fd 3
        self._r, w2 = os.pipe()  # chromium writes on fd 4 → we read
        self._profile = tempfile.mkdtemp()
        script = f"exec 3<&{r1} 4>&{w2}; exec {CHROMIUM} --headless --no-sandbox --disable-gpu " \
                 f"--remote-debugging-pipe --user-data-dir={self._profile} --window-size=1400,1000 about:blank"
        # TMPDIR inside the profile: Chromium's own scratch folders (org.chromium.Chromium.*) go with it
        self._proc = subprocess.Popen(["bash", "-c", script], pass_fds=(r1, w2), stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, env={**os.environ, "TMPDIR": self._profile})
        os.close(r1), os.close(w2)
        self._buf, self._id, self.events = b"", 0, []

    def _recv(self) -> dict:
        while b"\0" not in self._buf:
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed the pipe")
            self._buf += chunk
        msg, self._buf = self._buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method: str, session: str | None = None, **params) -> dict:
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        os.write(self._w, json.dumps(msg).encode() + b"\0")
        while True:
            m = self._recv()
            if m.get("id") == self._id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m["result"]
            self.events.append(m)

    def open(self, path: Path, settle_s: float = 1.5) -> "Page":
        target = self.call("Target.createTarget", url="about:blank")["targetId"]
        s = self.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        for m in ("Runtime.enable", "Log.enable", "Page.enable"):
            self.call(m, s)
        self.call("Emulation.setDeviceMetricsOverride", s, width=1400, height=1000, deviceScaleFactor=1, mobile=False)
        self.events.clear()
        self.call("Page.navigate", s, url=Path(path).resolve().as_uri())
        end = time.time() + 60
        while not any(e.get("method") == "Page.loadEventFired" and e.get("sessionId") == s for e in self.events):
            if time.time() > end:
                raise RuntimeError(f"{path} did not load in 60 s")
            self.events.append(self._recv())
        time.sleep(settle_s)
        self.call("Runtime.evaluate", s, expression="1")  # collect what arrived meanwhile
        return Page(self, s)

    def close(self):
        self._proc.kill()
        self._proc.wait()
        os.close(self._w), os.close(self._r)
        shutil.rmtree(self._profile, ignore_errors=True)


class Page:
    def __init__(self, browser: Browser, session: str):
        self.b, self.s = browser, session

    def eval(self, js: str):
        r = self.b.call("Runtime.evaluate", self.s, expression=js, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{js}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def errors(self) -> list[str]:
        """Console errors, uncaught exceptions and failed loads logged by the page so far."""
        out = []
        for e in self.b.events:
            if e.get("sessionId") != self.s:
                continue
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.exceptionThrown":
                out.append(json.dumps(p["exceptionDetails"])[:400])
            elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append(json.dumps(p.get("args"))[:400])
            elif m == "Log.entryAdded" and p["entry"].get("level") == "error":
                out.append(p["entry"].get("text", "")[:400])
        return out

    def screenshot(self, path: Path, full: bool = True) -> Path:
        data = self.b.call("Page.captureScreenshot", self.s, format="png", captureBeyondViewport=full)["data"]
        Path(path).write_bytes(base64.b64decode(data))
        return Path(path)
