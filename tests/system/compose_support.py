"""What the compose system test (compose_system_test.py) is made of: the Docker engine and the
compose command, compose projects, `dpc topic echo` from the host, the bench seen from the host
(errors to the target, lock, latest state), and small helpers. Constants name the test's
networks (in 10.99.0.0/16), image, domain and bench id."""

import glob
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

SKIP = 77
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
PREFIX = "10.99.77"          # the test's network (the compose default is 10.99.10)
SPLIT_PREFIX = "10.99.78"
IMAGE = "dpc-bench:systest"
DOMAIN = "0"
BENCH_ID = "systest"


def log(message):
    print(f"[compose-test {time.strftime('%H:%M:%S')}] {message}", flush=True)


def run(args, check=True, env=None, timeout=None, capture=True):
    result = subprocess.run(args, env=env, timeout=timeout, text=True,
                            stdout=subprocess.PIPE if capture else None,
                            stderr=subprocess.STDOUT if capture else None)
    if check and result.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} exited {result.returncode}:\n{result.stdout or ''}")
    return result


class Failure(Exception):
    pass


def expect(condition, message):
    if not condition:
        raise Failure(message)
    log(f"ok: {message}")


# --- the Docker engine ------------------------------------------------------------------------

class Engine:
    """Makes a Docker engine available; stops the one it started (only that one)."""

    def __init__(self):
        self.started = None

    def answers(self):
        return shutil.which("docker") and run(["docker", "info"], check=False, timeout=30).returncode == 0

    def ensure(self):
        if self.answers():
            return None
        if os.geteuid() != 0:
            return "no Docker engine answers and this user is not root (cannot install or start one)"
        missing = [p for p in ("docker.io", "docker-compose", "debootstrap")
                   if run(["dpkg-query", "-W", "-f=${Status}", p], check=False).stdout.find("install ok installed") < 0]
        if missing:
            log(f"installing {' '.join(missing)}")
            env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
            run(["apt-get", "update", "-qq"], env=env, timeout=600)
            run(["apt-get", "install", "-y", "-qq", "--no-install-recommends", *missing], env=env, timeout=1200)
        if not self.answers():
            dockerd = shutil.which("dockerd") or "/usr/sbin/dockerd"
            log("starting dockerd")
            self.log_file = open(os.path.join(tempfile.gettempdir(), "dpc-systest-dockerd.log"), "w")
            self.started = subprocess.Popen([dockerd], stdout=self.log_file, stderr=subprocess.STDOUT)
            deadline = time.monotonic() + 60
            while not self.answers():
                if self.started.poll() is not None or time.monotonic() > deadline:
                    return "dockerd did not start (see " + self.log_file.name + ")"
                time.sleep(0.5)
        return None

    def stop(self):
        if self.started and self.started.poll() is None:
            log(f"stopping the dockerd this test started (PID {self.started.pid})")
            self.started.send_signal(signal.SIGTERM)
            try:
                self.started.wait(60)
            except subprocess.TimeoutExpired:
                self.started.kill()


def compose_command():
    """`docker compose` (v2) where the plugin exists, else `docker-compose` (1.29)."""
    if run(["docker", "compose", "version"], check=False).returncode == 0:
        return ["docker", "compose"]
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    return None


def container_logs(container, tail):
    """The last `tail` lines a container wrote (every run of it), stdout then stderr."""
    result = run(["docker", "logs", "--tail", str(tail), container], check=False)
    return (result.stdout or "") + (result.stderr or "")


class Project:
    """One compose project: its own name, files and environment."""

    def __init__(self, base, name, files, env):
        self.base, self.name, self.files = base, name, files
        self.env = dict(os.environ, **env)

    def command_line(self, *args):
        command = [*self.base, "-p", self.name]
        for f in self.files:
            command += ["-f", os.path.join(REPO, f)]
        return [*command, *args]

    def __call__(self, *args, check=True, timeout=600, capture=True):
        return run(self.command_line(*args), check=check, env=self.env, timeout=timeout, capture=capture)

    def container(self, service):
        out = self("ps", "-q", service).stdout.strip().splitlines()
        if not out:
            raise Failure(f"no container for {service} in {self.name}")
        return out[-1]

    @property
    def label_filter(self):
        """`docker … --filter` for this project's containers, networks and volumes."""
        return f"label=com.docker.compose.project={self.name}"

    def restarts(self, service):
        """How often the restart policy has restarted `service`'s container."""
        return int(run(["docker", "inspect", "-f", "{{.RestartCount}}", self.container(service)]).stdout.strip() or 0)

    def logs(self, service, tail=200):
        """The last `tail` lines `service`'s container wrote (every run of it), stdout and stderr."""
        return container_logs(self.container(service), tail)

    def leftovers(self):
        found = {}
        for kind, command in (("containers", ["docker", "ps", "-a", "-q"]),
                              ("networks", ["docker", "network", "ls", "-q"]),
                              ("volumes", ["docker", "volume", "ls", "-q"])):
            ids = run([*command, "--filter", self.label_filter]).stdout.split()
            if ids:
                found[kind] = ids
        return found

    def down(self):
        self("down", "-v", "--remove-orphans", "-t", "10", check=False, timeout=300)

    def dump_stacks(self, path):
        """Every thread's stack of the dpc processes still running in this project's containers
        (gdb on the host, as root) into `path`: the evidence of a service stuck inside a library."""
        if os.geteuid() != 0 or shutil.which("gdb") is None:
            return None
        containers = run(["docker", "ps", "-q", "--filter", self.label_filter], check=False).stdout.split()
        with open(path, "w") as out:
            for container in containers:
                inspected = run(["docker", "inspect", "-f", "{{.Name}} {{.State.Pid}}", container],
                                check=False).stdout.split()
                if len(inspected) != 2:
                    continue
                name, pending, pids = inspected[0], [int(inspected[1])], []
                while pending:
                    pid = pending.pop()
                    pids.append(pid)
                    for task in glob.glob(f"/proc/{pid}/task/*/children"):
                        try:
                            pending += [int(c) for c in open(task).read().split()]
                        except OSError:
                            pass
                for pid in pids:
                    try:
                        comm = open(f"/proc/{pid}/comm").read().strip()
                    except OSError:
                        continue
                    if not comm.startswith("dpc"):
                        continue
                    result = run(["gdb", "-batch", "-nx", "-ex", f"set sysroot /proc/{pid}/root",
                                  "-ex", f"attach {pid}", "-ex", "thread apply all bt", "-ex", "detach"],
                                 check=False, timeout=120)
                    out.write(f"===== {name} pid {pid} ({comm})\n{result.stdout}\n")
        return path

    def print_logs(self, tail=80):
        """The last `tail` lines of every container's log (a failed check's evidence, which
        `down` would remove with the containers), then one line per container (state, exit code,
        restarts, its last log line): a CI log that keeps only the end of the output keeps that."""
        containers = run(["docker", "ps", "-a", "-q", "--filter", self.label_filter], check=False).stdout.split()
        brief = []
        for container in containers:
            name = run(["docker", "inspect", "-f", "{{.Name}} {{.State.Status}} {{.State.ExitCode}} {{.RestartCount}}",
                        container], check=False).stdout.split()
            lines = container_logs(container, tail).rstrip("\n").splitlines()
            log(f"--- the last {tail} log lines of {name[0] if name else container} ---")
            print("\n".join(lines), flush=True)
            if len(name) == 4:
                last = lines[-1] if lines else ""
                brief.append(f"  {name[0]}: {name[1]}, exit {name[2]}, {name[3]} restarts; last: "
                             f"{last[:160]}")
        log("containers at the failure:\n" + "\n".join(brief))


# --- watching from the host -------------------------------------------------------------------

class Echo:
    """`dpc topic echo TOPIC --json` on the host; every line kept with its arrival time."""

    def __init__(self, dpc, topic, profile):
        env = dict(os.environ, FASTRTPS_DEFAULT_PROFILES_FILE=profile)
        self.topic = topic
        self.process = subprocess.Popen(
            [dpc, "topic", "echo", topic, "--json", "--domain", DOMAIN, "--bench-id", BENCH_ID],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        self.lock = threading.Lock()
        self.items = []
        self.stderr = []
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=lambda: self.stderr.extend(self.process.stderr), daemon=True).start()

    def _read(self):
        for line in self.process.stdout:
            try:
                item = json.loads(line)
            except ValueError:
                continue
            with self.lock:
                self.items.append((time.monotonic(), item))

    def snapshot(self, since=0.0):
        with self.lock:
            return [(t, m) for t, m in self.items if t >= since]

    def count(self):
        with self.lock:
            return len(self.items)

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def host_profile(prefix, server, directory):
    path = os.path.join(directory, f"host-{prefix}.xml")
    args = [os.path.join(REPO, "deploy", "host-profile.sh"), "--prefix", prefix] + (["--server"] if server else [])
    with open(path, "w") as f:
        f.write(run(args).stdout)
    return path


def angle_deg(a, b):
    dot = sum(x * y for x, y in zip(a, b))
    cross = math.sqrt(sum(v * v for v in (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                           a[0] * b[1] - a[1] * b[0])))
    return math.degrees(math.atan2(cross, dot))


class Bench:
    """What the host sees of one bench: samples, driver states, the target."""

    def __init__(self, dpc, profile):
        self.samples = Echo(dpc, "dpc_stokes_sample", profile)
        self.states = Echo(dpc, "dpc_waveplate_state", profile)
        self.targets = Echo(dpc, "dpc_target", profile)

    def stop(self):
        for echo in (self.samples, self.states, self.targets):
            echo.stop()

    def target(self):
        items = self.targets.snapshot()
        if not items:
            return None
        point = items[-1][1].get("point")
        return point if items[-1][1].get("kind") == "TARGET_POINT" else None

    def errors(self, since, until=None):
        """(arrival time, angle from S_out to the target in degrees) of the samples seen."""
        target = self.target()
        if target is None:
            return []
        until = until or math.inf
        return [(t, angle_deg(m["s_out"], target)) for t, m in self.samples.snapshot(since) if t <= until]

    def wait(self, condition, timeout_s, what):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if condition():
                return True
            time.sleep(0.05)
        raise Failure(f"timed out after {timeout_s:.0f} s waiting for {what}; "
                      f"seen {self.samples.count()} samples, {self.states.count()} states; "
                      f"echo stderr: {''.join(self.states.stderr[-5:])}")

    def locked_since(self, since, window_s=0.2, threshold_deg=2.0, rate_floor_hz=200):
        """The end of the first window of window_s after `since` where every sample was within
        threshold_deg of the target, with at least rate_floor_hz samples a second; None if none."""
        errors = self.errors(since)
        start = 0
        for end in range(len(errors)):
            if errors[end][1] > threshold_deg:
                start = end + 1
                continue
            span = errors[end][0] - errors[start][0]
            if span >= window_s and (end - start + 1) >= rate_floor_hz * window_s:
                return errors[end][0]
        return None

    def latest_state(self):
        items = self.states.snapshot()
        return items[-1][1] if items else None


def cyclone_reads(probe, prefix, work, secure=False):
    """Another vendor's subscriber on the host (Cyclone DDS, deploy/cyclonedds/compose-host.xml),
    without credentials: it reads the bench if the bench is open, nothing if it is secure."""
    with open(os.path.join(REPO, "deploy", "cyclonedds", "compose-host.xml")) as f:
        config = f.read().replace("10.99.10.", prefix + ".")
    path = os.path.join(work, "cyclone-host.xml")
    with open(path, "w") as f:
        f.write(config)
    result = run([probe, "--domain", DOMAIN, "--bench-id", BENCH_ID, "--timeout-s", "15", "--states", "3"],
                 check=False, env=dict(os.environ, CYCLONEDDS_URI=f"file://{path}"), timeout=60)
    topics = set()
    for line in result.stdout.splitlines():
        try:
            topics.add(json.loads(line).get("topic"))
        except ValueError:
            pass
    if secure:
        expect("dpc_waveplate_state" not in topics and "dpc_device_description" not in topics,
               f"a Cyclone DDS subscriber without credentials reads nothing of the secure bench "
               f"(topics {sorted(t for t in topics if t)})")
        return
    expect(result.returncode == 0 and "dpc_waveplate_state" in topics,
           f"a Cyclone DDS subscriber on the host reads the bench (topics {sorted(t for t in topics if t)})")


def loop_latencies_us(bench, since):
    """Sorted latencies from a sample's publication (polarimeter) to the driver's receipt of the
    command that answers it, for the states seen since `since` (one host clock for all containers)."""
    published = {m["sequence_number"]: m["publish_time_ns"] for _, m in bench.samples.snapshot(since - 1.0)}
    return sorted((m["command_receive_time_ns"] - published[m["answers_sample"]]) * 1e-3
                  for _, m in bench.states.snapshot(since)
                  if m["mode"] == "DRIVER_ACTIVE" and m["answers_sample"] in published)


def max_abs_difference(a, b):
    return max(abs(x - y) for x, y in zip(a, b))


# --- the dashboard, as a browser would reach it ----------------------------------------------

def free_port():
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http_get(port, path="/"):
    """GET http://127.0.0.1:port/path → (status, headers, body)."""
    import http.client
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        connection.request("GET", path)
        response = connection.getresponse()
        return response.status, dict(response.getheaders()), response.read().decode("utf-8", "replace")
    finally:
        connection.close()


def dashboard_snapshots(port, wanted, timeout_s=20.0):
    """Opens the dashboard's WebSocket (/ws) as the page does (its own Origin) and returns the
    first snapshot for which wanted(snapshot) holds, or the last one seen (None if none). A
    dashboard that closes the socket (restarted by its restart policy) is connected to again."""
    deadline = time.monotonic() + timeout_s
    seen = []
    while True:
        try:
            return _dashboard_snapshots_until(port, wanted, deadline, seen)
        except (Failure, OSError) as error:
            if time.monotonic() + 1.0 >= deadline:
                if not seen:
                    raise
                return seen[-1]
            log(f"the dashboard's WebSocket ended ({error}); connecting again")
            time.sleep(1.0)


def _dashboard_snapshots_until(port, wanted, deadline, seen):
    """One connection of dashboard_snapshots: each snapshot is appended to `seen`."""
    import base64
    import socket
    import struct
    key = base64.b64encode(os.urandom(16)).decode()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall((f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                   f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                   f"Origin: http://127.0.0.1:{port}\r\n\r\n").encode())
        buffer = b""
        while b"\r\n\r\n" not in buffer:
            chunk = s.recv(4096)
            if not chunk:
                raise Failure("the dashboard closed the WebSocket handshake")
            buffer += chunk
        head, buffer = buffer.split(b"\r\n\r\n", 1)
        status_line = head.split(b"\r\n")[0]
        if b" 101 " not in status_line:
            raise Failure(f"the dashboard refused the WebSocket: {status_line!r}")

        def take(n):
            nonlocal buffer
            while len(buffer) < n:
                chunk = s.recv(65536)
                if not chunk:
                    raise Failure("the dashboard closed the WebSocket")
                buffer += chunk
            out, buffer = buffer[:n], buffer[n:]
            return out

        message = b""
        while time.monotonic() < deadline:
            first, second = take(2)
            opcode, length = first & 0x0F, second & 0x7F
            if length == 126:
                length = struct.unpack(">H", take(2))[0]
            elif length == 127:
                length = struct.unpack(">Q", take(8))[0]
            payload = take(length)  # a server's frames are not masked
            if opcode == 8:
                raise Failure("the dashboard closed the WebSocket")
            if opcode in (9, 10):  # ping/pong: the page's browser answers; not needed here
                continue
            message += payload
            if not first & 0x80:
                continue
            text, message = message.decode("utf-8", "replace"), b""
            try:
                snapshot = json.loads(text)
            except ValueError:
                continue
            if snapshot.get("type") != "snapshot":
                continue
            seen.append(snapshot)
            if wanted(snapshot):
                return snapshot
    return seen[-1] if seen else None
