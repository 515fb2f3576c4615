"""Every client under docs/clients/ against `emoshift serve` for longer than a lease (issue 37).

receive_marker.py subscribes, renews its lease and answers /subscribe/challenge: run from
127.0.0.1 (no challenge) and from 127.0.0.2 (standing in for another PC, challenged), each for
32 s against the default 10 s lease, it must still print frames at the end. control_session.sh
(liblo's oscsend) drives the same daemon meanwhile: its recording must land on disk and the
stream must not stop. Prints PASS/FAIL per check and "N passed, M failed"; exits 1 on a failure.
"""
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time

EMOSHIFT = os.environ["EMOSHIFT"]
HERE = os.path.dirname(os.path.abspath(__file__))
CLIENTS = os.path.join(HERE, "..", "docs", "clients")
RUN_S = 32.0
results = []


def check(name, ok, detail=""):
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else ": " + str(detail)), flush=True)
    results.append(bool(ok))


def free_port(host="127.0.0.1"):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def run(args, cwd):
    subprocess.run([EMOSHIFT] + args, check=True, cwd=cwd, stdout=subprocess.DEVNULL)


class Receiver:
    """receive_marker.py in the background, each output line kept with its arrival time."""

    def __init__(self, bind, control):
        self.port = free_port(bind)
        self.lines = []
        self.proc = subprocess.Popen(
            [sys.executable, os.path.join(CLIENTS, "receive_marker.py"), "--daemon",
             f"127.0.0.1:{control}", "--bind", bind, "--port", str(self.port), "--marker", "3",
             "--seconds", str(RUN_S)],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.started = time.monotonic()
        threading.Thread(target=self.read, daemon=True).start()

    def read(self):
        for line in self.proc.stdout:
            self.lines.append((time.monotonic() - self.started, line.rstrip()))

    def frames_after(self, t):
        return sum(1 for at, line in self.lines if at >= t and line.startswith("frame"))

    def longest_gap(self):
        times = [at for at, line in self.lines if line.startswith("frame")]
        return max((b - a for a, b in zip(times, times[1:])), default=RUN_S)


def main():
    work = tempfile.mkdtemp(prefix="emoshift-clients-")
    run(["synth", "--out", "session", "--seed", "5", "--sentences", "2", "--emotions",
         "neutral,happy", "--format", "csv"], work)
    run(["train", "session/s01_neutral.csv", "--out", "model.json", "--components", "8",
         "--restarts", "1", "--head-reference", "none"], work)
    listen, control = free_port(), free_port()
    with open(os.path.join(work, "emoshift.toml"), "w") as f:
        f.write(f'model = "model.json"\nlisten = "127.0.0.1:{listen}"\n'
                f'control = "127.0.0.1:{control}"\ncontrol_allow = ["127.0.0.0/8"]\n')
    log = open(os.path.join(work, "serve.log"), "w+")
    serve = subprocess.Popen([EMOSHIFT, "serve", "--config", "emoshift.toml"], cwd=work,
                             stdout=log, stderr=subprocess.STDOUT)
    replay = subprocess.Popen([EMOSHIFT, "replay", "session/s01_neutral.csv", "--to",
                               f"127.0.0.1:{listen}", "--loop"], cwd=work,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(1.5)
        here, remote = Receiver("127.0.0.1", control), Receiver("127.0.0.2", control)
        time.sleep(5)
        env = dict(os.environ, DAEMON_HOST="127.0.0.1", DAEMON_PORT=str(control), OUT=work)
        shell = subprocess.run(["bash", os.path.join(CLIENTS, "control_session.sh")], env=env,
                               capture_output=True, text=True, timeout=60)
        check("control_session.sh runs to its end", shell.returncode == 0, shell.stderr[-500:])
        for r in (here, remote):
            r.proc.wait(RUN_S + 20)
        time.sleep(0.3)
        for name, r in (("127.0.0.1", here), ("127.0.0.2 (another PC)", remote)):
            check(f"receive_marker.py from {name} still receives after 30 s",
                  r.frames_after(30.0) > 50, r.lines[-3:])
            check(f"receive_marker.py from {name}: no pause over 1 s in {RUN_S:.0f} s",
                  r.longest_gap() < 1.0, r.longest_gap())
        check("receive_marker.py from 127.0.0.2 answered the daemon's challenge",
              any("challenged" in line for _, line in remote.lines), remote.lines[:3])
        check("receive_marker.py from 127.0.0.1 was not challenged",
              not any("challenged" in line for _, line in here.lines), here.lines[:3])
        rec = [os.path.join(work, n) for n in ("edited.c3d", "input.c3d")]
        check("control_session.sh's recording is on disk (edited and raw input)",
              all(os.path.exists(p) and os.path.getsize(p) > 0 for p in rec), rec)
    finally:
        replay.terminate()
        serve.terminate()
        serve.wait(10)
        replay.wait(10)
    log.seek(0)
    text = log.read()
    check("serve dropped no subscription for want of renewal", "not renewed" not in text,
          [ln for ln in text.splitlines() if "not renewed" in ln][:2])
    subprocess.run(["rm", "-rf", work])
    failed = results.count(False)
    print("interop clients: %d passed, %d failed" % (len(results) - failed, failed))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
