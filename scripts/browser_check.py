#!/usr/bin/env python3
"""The monitor page in a real browser (run by scripts/browser-check, which starts the daemon),
then the calibration session's performer page (this script starts `emoshift session`).

Environment: BIN (emoshift), WORK (folder with model.json and session/), OUT (screenshots),
URL (the page with its token, as `emoshift serve` printed it), FRAMES and CONTROL (the daemon's
sockets). Prints PASS/FAIL per check and "N passed, M failed"; exit status 1 on any failure.
Only loopback addresses; every wait is bounded.
"""

import http.client
import os
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.parse

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By

BIN, WORK, OUT, URL = (os.environ[k] for k in ("BIN", "WORK", "OUT", "URL"))
FRAMES = os.environ["FRAMES"].split(":")
CONTROL = os.environ["CONTROL"].split(":")
CONTROL = (CONTROL[0], int(CONTROL[1]))
FRAMES = (FRAMES[0], int(FRAMES[1]))
PAGE = urllib.parse.urlsplit(URL)
TOKEN = urllib.parse.parse_qs(PAGE.query).get("token", [""])[0]
results = []


def check(name, ok, detail=""):
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else ": " + str(detail)), flush=True)
    results.append(bool(ok))
    return ok


def wait_for(what, timeout=15.0, every=0.1):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = what()
        if value:
            return value
        time.sleep(every)
    return what()


# --- OSC, just enough: messages in and out, bundles in -----------------------------------

def pad(b):
    return b + b"\0" * (4 - len(b) % 4)


def osc(address, *args):
    tags, data = ",", b""
    for a in args:
        if isinstance(a, str):
            tags, data = tags + "s", data + pad(a.encode())
        elif isinstance(a, float):
            tags, data = tags + "f", data + struct.pack(">f", a)
        else:
            tags, data = tags + "i", data + struct.pack(">i", a)
    return pad(address.encode()) + pad(tags.encode()) + data


def read_str(b, at):
    end = b.index(b"\0", at)
    return b[at:end].decode(), (end // 4 + 1) * 4


def parse_message(b):
    address, at = read_str(b, 0)
    tags, at = read_str(b, at)
    args = []
    for t in tags[1:]:
        if t in "if":
            args.append(struct.unpack_from(">i" if t == "i" else ">f", b, at)[0])
            at += 4
        elif t in "hd":
            args.append(struct.unpack_from(">q" if t == "h" else ">d", b, at)[0])
            at += 8
        elif t == "s":
            s, at = read_str(b, at)
            args.append(s)
        elif t == "b":
            (n,) = struct.unpack_from(">i", b, at)
            args.append(b[at + 4 : at + 4 + n])
            at += 4 + (n + 3) // 4 * 4
    return address, args


def messages(b):
    if not b.startswith(b"#bundle\0"):
        yield parse_message(b)
        return
    at = 16
    while at < len(b):
        (n,) = struct.unpack_from(">i", b, at)
        yield from messages(b[at + 4 : at + 4 + n])
        at += 4 + n


def status():
    """The daemon's /status as a dict."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.settimeout(3)
    try:
        s.sendto(osc("/status"), CONTROL)
        _, args = parse_message(s.recv(65536))
        return dict(zip(args[0::2], args[1::2]))
    finally:
        s.close()


# --- the stage around the page --------------------------------------------------------------

class Relay(threading.Thread):
    """Forwards the replay's datagrams to the daemon; with `repeat` set, sends each twice (the
    second a duplicate frame the daemon must drop and count)."""

    def __init__(self):
        super().__init__(daemon=True)
        self.inbound = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.inbound.bind(("127.0.0.1", 0))
        self.inbound.settimeout(0.2)
        self.out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.out.bind(("127.0.0.1", 0))
        self.repeat = False
        self.stop = False

    def run(self):
        while not self.stop:
            try:
                data = self.inbound.recv(65536)
            except socket.timeout:
                continue
            for _ in range(2 if self.repeat else 1):
                self.out.sendto(data, FRAMES)


class Subscriber(threading.Thread):
    """An OSC client subscribed with the compact profile: keeps the last /emoshift/state."""

    def __init__(self):
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.state = None
        self.frames = 0
        self.confirmed = False
        self.stop = False

    def run(self):
        port = self.sock.getsockname()[1]
        renewed = 0.0
        while not self.stop:
            if time.monotonic() - renewed > 3:
                self.sock.sendto(osc("/subscribe", port, "compact"), CONTROL)
                renewed = time.monotonic()
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                continue
            for address, args in messages(data):
                if address == "/subscribe/confirm":
                    self.confirmed = True
                elif address == "/emoshift/state":
                    self.state = (args[0], args[1])
                elif address == "/mocap/frame":
                    self.frames += 1


def browser():
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--disable-dev-shm-usage", "--hide-scrollbars", "--window-size=1440,1000",
                 f"--user-data-dir={WORK}/chromium-profile"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    driver.set_page_load_timeout(20)
    driver.set_script_timeout(10)
    return driver


def js(driver, script):
    return driver.execute_script(script)


# Pixels of the edited markers' colour (#f2a33a) in a canvas: the views show markers.
MARKER_PIXELS = """
const c = document.getElementById(arguments[0]);
const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
let n = 0;
for (let i = 0; i < d.length; i += 4) {
  if (Math.abs(d[i] - 242) < 30 && Math.abs(d[i + 1] - 163) < 30 && Math.abs(d[i + 2] - 58) < 40) n++;
}
return n;
"""


def ws_handshake(origin, cookie):
    """The status code the page's WebSocket answers an upgrade from `origin`."""
    conn = http.client.HTTPConnection(PAGE.hostname, PAGE.port, timeout=5)
    headers = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
               "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==", "Origin": origin}
    if cookie:
        headers["Cookie"] = f"emoshift_monitor_{PAGE.port}={TOKEN}"
    conn.request("GET", "/ws", headers=headers)
    code = conn.getresponse().status
    conn.close()
    return code


def refusals(driver):
    base = f"http://{PAGE.netloc}"
    driver.get(f"{base}/?token=not-{TOKEN[4:]}")
    body = driver.find_element(By.TAG_NAME, "body").text
    check("a wrong token gets the login prompt and nothing else",
          "not this daemon's" in body and js(driver, "return window.emoshift === undefined"), body[:200])
    conn = http.client.HTTPConnection(PAGE.hostname, PAGE.port, timeout=5)
    conn.request("GET", "/js/main.js")
    r = conn.getresponse()
    page = r.read().decode(errors="replace")
    check("without the token the page's files are not served (401, login prompt)",
          r.status == 401 and "token" in page and "import" not in page, r.status)
    check("without the token the WebSocket is refused", ws_handshake(base, False) == 401)
    check("a WebSocket from a foreign origin is refused even with the token",
          ws_handshake("http://evil.example", True) == 403)
    check("the WebSocket from the page's own origin upgrades", ws_handshake(base, True) == 101)


def views(driver):
    driver.get(URL)
    ok = wait_for(lambda: js(driver, "return window.emoshift && window.emoshift.drawn > 20"), 20)
    check("the token opens the page and it draws the replayed stream", ok)
    check("the token leaves the address bar", "token=" not in driver.current_url, driver.current_url)
    time.sleep(1.5)  # a second of the strip chart and the health
    front, side = (js(driver, MARKER_PIXELS.replace("arguments[0]", repr(v))) for v in ("front", "side"))
    check("markers in the front and the side view", front > 200 and side > 200, (front, side))
    driver.save_screenshot(f"{OUT}/monitor-desktop.png")


def hover_and_rotate(driver):
    """The marker under the pointer is named; the rotate control turns the views."""
    canvas = driver.find_element(By.ID, "front")
    x, y = js(driver, "return document.getElementById('front').markerPoints[0]")
    w, h = canvas.size["width"], canvas.size["height"]
    ActionChains(driver).move_to_element_with_offset(canvas, int(x - w / 2), int(y - h / 2)).perform()
    label = js(driver, "const s = window.emoshift.streams.get(window.emoshift.selected);"
                       "return s.model.labels[0];")
    text = wait_for(lambda: js(driver, "const e = document.getElementById('hover');"
                                       "return e.hidden ? '' : e.textContent"), 3)
    check("the marker under the pointer is named", label and text.startswith(label), (label, text))
    before = js(driver, "return document.getElementById('front').markerPoints.map(p => p[0])")
    js(driver, "const r = document.getElementById('yaw'); r.value = '60';"
               "r.dispatchEvent(new Event('input'))")
    time.sleep(0.3)
    after = js(driver, "return document.getElementById('front').markerPoints.map(p => p[0])")
    moved = max(abs(a - b) for a, b in zip(before, after))
    check("the rotate control turns the views", moved > 5, moved)
    js(driver, "const r = document.getElementById('yaw'); r.value = '0';"
               "r.dispatchEvent(new Event('input'))")


def control(driver, sub):
    happy = driver.find_element(By.CSS_SELECTOR, '.emo-btn[data-emotion="happy"]')
    happy.click()
    slider = driver.find_element(By.ID, "amount")
    width = slider.size["width"]
    ActionChains(driver).move_to_element_with_offset(slider, int(width * 0.25), 0).click().perform()
    value = float(slider.get_attribute("value"))
    check("the amount slider moved", 0.6 < value < 0.9, value)
    seen = wait_for(lambda: sub.state and sub.state[0] == "happy" and abs(sub.state[1] - value) < 0.02
                    and sub.state, 10)
    check("an OSC subscriber sees the edited output's state change: target happy, the slider's amount",
          seen, f"subscriber saw {sub.state}, slider {value}")
    shown = wait_for(lambda: js(driver, "return document.getElementById('st-target').textContent") == "happy", 5)
    check("the page shows the state the daemon reports", shown)
    check("the button of the reported target is lit",
          "active" in happy.get_attribute("class"))
    driver.save_screenshot(f"{OUT}/monitor-happy.png")


def drops(driver, relay):
    read = lambda: int(js(driver, "return document.getElementById('stream-drops').dataset.value || '0'"))
    before = read()
    relay.repeat = True
    rose = wait_for(lambda: read() > before + 10, 10)
    relay.repeat = False
    st = status()
    dup = [v for k, v in st.items() if k.endswith("/dropped_duplicate")]
    check("the page's drop counter rises while frames are dropped (duplicates)", rose,
          f"{before} -> {read()}")
    check("and /status counts the same drops", dup and max(dup) >= read() - 5, (dup, read()))


def recording(driver):
    path = driver.find_element(By.ID, "rec-path")
    path.clear()
    path.send_keys("from-the-page.c3d")
    driver.find_element(By.ID, "rec-start").click()
    state = lambda: js(driver, "return document.getElementById('rec-state').textContent")
    check("the page starts a recording and shows it", wait_for(lambda: "from-the-page.c3d" in state(), 5), state())
    driver.find_element(By.ID, "rec-stop").click()
    check("and stops it; the file is there", wait_for(lambda: state() == "idle", 5)
          and wait_for(lambda: os.path.exists(f"{WORK}/from-the-page.c3d")
                                  and os.path.getsize(f"{WORK}/from-the-page.c3d") > 1000, 5), state())


def phone(driver):
    driver.set_window_size(390, 844)
    time.sleep(1.0)
    fits = js(driver, "return document.documentElement.scrollWidth <= window.innerWidth + 1")
    check("a phone-size viewport (390 px) needs no sideways scrolling", fits,
          js(driver, "return [document.documentElement.scrollWidth, window.innerWidth]"))
    front = js(driver, MARKER_PIXELS.replace("arguments[0]", "'front'"))
    check("the phone layout still draws the face", front > 50, front)
    driver.save_screenshot(f"{OUT}/monitor-phone.png")
    js(driver, "document.querySelector('.health-panel').scrollIntoView()")
    driver.save_screenshot(f"{OUT}/monitor-phone-health.png")


# --- the calibration session's performer page ----------------------------------------------

SECRET = "stage-secret-1"
SCRIPT = """emotions = ["neutral", "happy"]
[[sentence]]
text = "The birch canoe slid on the smooth planks."
seconds = [0.5, 60.0]
[[sentence]]
text = "Glue the sheet to the dark blue background."
seconds = [0.5, 60.0]
"""


def free_udp():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Session:
    """`emoshift session` fed by a looping replay, its page at `page_ip`, until `close`."""

    def __init__(self, name, page_ip, *extra):
        self.dir = f"{WORK}/{name}"
        with open(f"{WORK}/{name}-script.toml", "w") as f:
            f.write(SCRIPT)
        frames, self.control = free_udp(), ("127.0.0.1", free_udp())
        self.log = open(f"{WORK}/{name}.out", "w+")
        self.proc = subprocess.Popen(
            [BIN, "session", self.dir, "--listen", f"127.0.0.1:{frames}", "--no-keyboard",
             "--script", f"{WORK}/{name}-script.toml", "--control", f"127.0.0.1:{self.control[1]}",
             "--monitor", f"{page_ip}:0", *extra],
            stdout=self.log, stderr=subprocess.DEVNULL)
        self.replay = subprocess.Popen([BIN, "replay", f"{WORK}/session/s01_neutral.c3d", "--to",
                                        f"127.0.0.1:{frames}", "--loop"],
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.url = wait_for(self.page_url, 15)

    def page_url(self):
        self.log.seek(0)
        for line in self.log.read().splitlines():
            if line.startswith("performer view: "):
                return line.split(": ", 1)[1]
        return None

    def status(self):
        """The session's /session/status: (take, takes, sentence, emotion, state, text)."""
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind(("127.0.0.1", 0))
        s.settimeout(3)
        try:
            s.sendto(osc("/session/status"), self.control)
            return parse_message(s.recv(65536))[1]
        finally:
            s.close()

    def close(self):
        for p in (self.replay, self.proc):
            p.terminate()
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
        self.log.close()


PAGE_STATE = """const v = window.emoshiftSession && window.emoshiftSession.last();
if (!v) return null;
const shown = [...document.querySelectorAll('#controls button')].filter(b => !b.hidden).map(b => b.id);
return {take: v.take, state: v.state, emotion: document.getElementById('emotion').textContent,
        text: document.getElementById('text').textContent, why: document.getElementById('why').textContent,
        light: document.getElementById('light').className, shown};"""


def post_control(origin, cookie, url):
    """The status of a /control post of /session/start from `origin` (with the cookie or not)."""
    page = urllib.parse.urlsplit(url)
    token = urllib.parse.parse_qs(page.query).get("token", [""])[0]
    conn = http.client.HTTPConnection(page.hostname, page.port, timeout=5)
    headers = {"Origin": origin, "Content-Type": "application/octet-stream"}
    if cookie:
        headers["Cookie"] = f"emoshift_monitor_{page.port}={token}"
    conn.request("POST", "/control", body=osc("/session/start", SECRET), headers=headers)
    code = conn.getresponse().status
    conn.close()
    return code


def session_page(driver):
    """The prompt, presses that start and stop takes, the page advancing, refusals shown."""
    driver.set_window_size(1440, 1000)
    sess = Session("perf", "127.0.0.2", "--control-secret", SECRET)
    try:
        check("the session prints its performer page with a token", sess.url and "token=" in sess.url,
              sess.url)
        base = urllib.parse.urlsplit(sess.url)
        check("the page refuses a press without its token (401)",
              post_control(f"http://{base.netloc}", False, sess.url) == 401)
        check("and a press from another site's page, even with the token (403)",
              post_control("http://evil.example", True, sess.url) == 403)
        driver.get(f"http://{base.netloc}/?token=wrong-{SECRET}")
        check("a wrong token gets the login prompt",
              "not this daemon's" in driver.find_element(By.TAG_NAME, "body").text)
        driver.get(sess.url)
        state = lambda: js(driver, PAGE_STATE)
        st = sess.status()
        shown = wait_for(lambda: (state() or {}).get("emotion", "").lower() == st[3] and state(), 10)
        check("the page shows the prompt: the emotion and the sentence, take 1",
              shown and shown["text"] == st[5] and shown["take"] == 1, (shown, st))
        check("waiting: start, skip and back shown, stop hidden",
              shown and {"start", "skip", "back"} <= set(shown["shown"]) and "stop" not in shown["shown"],
              shown)
        size = js(driver, "return [parseFloat(getComputedStyle(document.getElementById('text')).fontSize),"
                          "document.getElementById('start').getBoundingClientRect().height]")
        check("readable from a few metres: sentence text >= 60 px, buttons >= 100 px tall at 1000 px",
              size[0] >= 60 and size[1] >= 100, size)
        driver.find_element(By.ID, "start").click()
        why = wait_for(lambda: "secret" in (state() or {}).get("why", "") and state()["why"], 5)
        check("a press without the control secret is refused and the page says why",
              why and sess.status()[4] == "waiting", why)
        driver.find_element(By.ID, "secret").send_keys(SECRET)
        takes(driver, sess, state)
    finally:
        sess.close()


def takes(driver, sess, state):
    for n in (1, 2):
        driver.find_element(By.ID, "start").click()
        rec = wait_for(lambda: (state() or {}).get("state") == "recording" and state(), 5)
        check(f"take {n}: the start button records (light on, only stop shown)",
              rec and rec["light"] == "on" and rec["shown"] == ["stop"] and sess.status()[4] == "recording",
              rec)
        time.sleep(1.5)
        driver.find_element(By.ID, "stop").click()
        moved = wait_for(lambda: (state() or {}).get("take") == n + 1 and state(), 10)
        check(f"take {n}: the stop button stops it, it is accepted and the page advances to take {n + 1}",
              moved and moved["state"] == "waiting" and sess.status()[0] == n, (moved, sess.status()))
        if n == 1:
            driver.save_screenshot(f"{OUT}/session-page.png")
    written = [f for f in os.listdir(sess.dir) if f.endswith(".c3d")]
    check("both takes are written and listed", len(written) == 2
          and os.path.exists(f"{sess.dir}/session.toml"), written)


def session_refused_peer(driver):
    """A page whose address the allow-list leaves out is view only and says why."""
    sess = Session("view-only", "127.0.0.1", "--control-allow", "192.0.2.0/24")
    try:
        driver.get(sess.url)
        state = lambda: js(driver, PAGE_STATE)
        why = wait_for(lambda: "not allowed" in (state() or {}).get("why", "") and state()["why"], 10)
        disabled = js(driver, "return [...document.querySelectorAll('#controls button')].every(b => b.disabled)")
        check("a page from a peer the allow-list refuses is view only and says why", why and disabled, why)
        answer = js(driver, "const b = new Uint8Array([47,115,101,115,115,105,111,110,47,115,116,97,114,116,0,0,44,0,0,0]);"
                            "const x = new XMLHttpRequest(); x.open('POST', '/control', false); x.send(b);"
                            "return JSON.parse(x.responseText);")
        # (The OSC status is refused to this peer too: the page's own view says the state.)
        time.sleep(0.5)
        check("and a press from it is refused with the reason, the take not started",
              not answer["ok"] and "not allowed" in answer["error"] and state()["state"] == "waiting",
              (answer, state()))
    finally:
        sess.close()


def main():
    relay, sub = Relay(), Subscriber()
    relay.start()
    sub.start()
    replay = subprocess.Popen([BIN, "replay", f"{WORK}/session/s01_neutral.c3d", "--to",
                               f"127.0.0.1:{relay.inbound.getsockname()[1]}", "--loop"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    driver = browser()
    try:
        check("the OSC subscriber is confirmed and receives frames",
              wait_for(lambda: sub.confirmed and sub.frames > 10, 10))
        for step in (lambda: refusals(driver), lambda: views(driver), lambda: hover_and_rotate(driver),
                     lambda: control(driver, sub),
                     lambda: drops(driver, relay), lambda: recording(driver), lambda: phone(driver),
                     lambda: session_page(driver), lambda: session_refused_peer(driver)):
            try:
                step()
            except Exception as e:  # one broken step must not hide the others' results
                check(f"step {step.__code__.co_names[0]}", False, repr(e))
    finally:
        driver.quit()
        replay.terminate()
        replay.wait(5)
        relay.stop = sub.stop = True
    passed = sum(results)
    print(f"screenshots: {OUT}/monitor-desktop.png, monitor-happy.png, monitor-phone.png, session-page.png")
    print(f"{passed} passed, {len(results) - passed} failed")
    return 0 if passed == len(results) and results else 1


if __name__ == "__main__":
    sys.exit(main())
