#!/usr/bin/env python3
"""System test: the bench in Docker containers (docker-compose.yml), watched from the host.

  compose_system_test.py --dpc build/tools/dpc/dpc [--keep-going] [--rate-hz N]

Steps (each prints what it saw; the figures at the end are the issue's closing figures):
  1. The Docker engine: used if it answers; else, as root, installed (apt: docker.io,
     docker-compose, debootstrap) and started (and stopped again at the end, by PID); else the
     test is skipped (exit 77) with the reason.
  2. The base image: deploy/make-base-image.sh builds debian:bookworm-slim where it is missing.
  3. Build the image; `up` the bench with the standby controller; the output locks to the target,
     seen from the host by `dpc topic echo` through the network's gateway.
  4. `kill` of the controller container: the standby takes over, the output stays locked.
  5. `docker network disconnect` of the solver for longer than the deadlines: the driver holds
     and says why; reconnect: control resumes from the held φ, without a jump.
  6. `down` leaves no container, network or volume of the project.
  7. Split deployment: the bench (with its discovery server) and the solver as two compose
     projects; the solver's controller locks the bench's output.
Every container network is internal with a subnet in 10.99.0.0/16; host-side participants are
whitelisted to the bridge's gateway only.
"""

import argparse
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


class Project:
    """One compose project: its own name, files and environment."""

    def __init__(self, base, name, files, env):
        self.base, self.name, self.files = base, name, files
        self.env = dict(os.environ, **env)

    def __call__(self, *args, check=True, timeout=600, capture=True):
        command = [*self.base, "-p", self.name]
        for f in self.files:
            command += ["-f", os.path.join(REPO, f)]
        return run([*command, *args], check=check, env=self.env, timeout=timeout, capture=capture)

    def container(self, service):
        out = self("ps", "-q", service).stdout.strip().splitlines()
        if not out:
            raise Failure(f"no container for {service} in {self.name}")
        return out[-1]

    def leftovers(self):
        label = f"label=com.docker.compose.project={self.name}"
        found = {}
        for kind, command in (("containers", ["docker", "ps", "-a", "-q"]),
                              ("networks", ["docker", "network", "ls", "-q"]),
                              ("volumes", ["docker", "volume", "ls", "-q"])):
            ids = run([*command, "--filter", label]).stdout.split()
            if ids:
                found[kind] = ids
        return found

    def down(self):
        self("down", "-v", "--remove-orphans", "-t", "10", check=False, timeout=300)


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


def cyclone_reads(probe, prefix, work):
    """Another vendor's subscriber on the host (Cyclone DDS, deploy/cyclonedds/compose-host.xml)."""
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


def failover_and_hold(args, base, work):
    figures = {}
    project = Project(base, "dpcsystest", ["docker-compose.yml"], {
        "DPC_NET_PREFIX": PREFIX, "DPC_IMAGE": IMAGE, "DPC_DOMAIN": DOMAIN, "DPC_BENCH_ID": BENCH_ID,
        "DPC_RATE_HZ": str(args.rate_hz), "DPC_SCRAMBLER_RAD_PER_S": str(args.scrambler_rad_per_s),
        "COMPOSE_PROFILES": "standby"})
    project.down()
    bench = None
    try:
        log("build (first build compiles the services: minutes on 2 cores)")
        started = time.monotonic()
        project("build", capture=False, timeout=3600)
        figures["build_s"] = time.monotonic() - started
        size = int(run(["docker", "image", "inspect", "-f", "{{.Size}}", IMAGE]).stdout.strip())
        figures["image_mb"] = size / 1e6
        base_image = project.env.get("DPC_BASE_IMAGE", "debian:bookworm-slim")
        figures["base_image_mb"] = int(run(["docker", "image", "inspect", "-f", "{{.Size}}", base_image]).stdout) / 1e6
        log(f"image {IMAGE}: {figures['image_mb']:.1f} MB (base {figures['base_image_mb']:.1f} MB)")

        log("up (bench, controller, standby)")
        up_started = time.monotonic()
        project("up", "-d", timeout=300)
        figures["up_command_s"] = time.monotonic() - up_started
        bench = Bench(args.dpc, host_profile(PREFIX, False, work))
        bench.wait(lambda: bench.locked_since(up_started) is not None, 90, "the output to lock")
        figures["up_to_locked_s"] = bench.locked_since(up_started) - up_started
        log(f"locked {figures['up_to_locked_s']:.2f} s after `up` (the command took {figures['up_command_s']:.2f} s)")
        # The lock is judged from the samples; the states arrive on their own topic.
        bench.wait(lambda: bench.latest_state() is not None, 20, "the driver's state")
        state = bench.latest_state()
        expect(state["mode"] == "DRIVER_ACTIVE" and state["obeyed_controller_id"] == "main",
               f"the driver obeys the main controller ({state['reason']})")
        network = f"{project.name}_bench"
        info = json.loads(run(["docker", "network", "inspect", network]).stdout)[0]
        subnets = [c["Subnet"] for c in info["IPAM"]["Config"]]
        expect(info["Internal"] and subnets == [f"{PREFIX}.0/24"],
               f"the network {network} is internal, subnet {subnets} (no route out of the machine)")
        if args.cyclone_probe:
            cyclone_reads(args.cyclone_probe, PREFIX, work)

        # --- kill of the controller container → the standby takes over ---------------------------
        time.sleep(1.0)
        before_kill = time.monotonic()
        figures["host_sample_rate_hz"] = len(bench.samples.snapshot(before_kill - 1.0)) / 1.0
        latencies = loop_latencies_us(bench, before_kill - 1.0)
        if latencies:
            figures["loop_latency_p50_us"] = latencies[len(latencies) // 2]
            figures["loop_latency_p99_us"] = latencies[int(len(latencies) * 0.99)]
            log(f"loop latency (sample published → command received by the driver): p50 "
                f"{figures['loop_latency_p50_us']:.0f} µs, p99 {figures['loop_latency_p99_us']:.0f} µs")
        log(f"samples seen on the host: {figures['host_sample_rate_hz']:.0f} per second (polarimeter at {args.rate_hz} Hz)")
        errors_before = [e for _, e in bench.errors(before_kill - 1.0, before_kill)]
        log("docker kill of the controller container")
        project("kill", "-s", "SIGKILL", "controller")
        killed = time.monotonic()
        bench.wait(lambda: any(m["obeyed_controller_id"] == "standby" and m["answers_sample"] > 0
                               for _, m in bench.states.snapshot(killed)), 20, "the standby to take over")
        time.sleep(1.5)
        states = [m for _, m in bench.states.snapshot(before_kill)]
        last_main = max((m["command_receive_time_ns"] for m in states
                         if m["obeyed_controller_id"] == "main" and m["answers_sample"] > 0), default=None)
        first_standby = min((m["command_receive_time_ns"] for m in states
                             if m["obeyed_controller_id"] == "standby" and m["answers_sample"] > 0
                             and (last_main is None or m["command_receive_time_ns"] > last_main)), default=None)
        expect(last_main is not None and first_standby is not None, "commands of both controllers seen")
        figures["failover_gap_ms"] = (first_standby - last_main) * 1e-6
        after = [e for _, e in bench.errors(killed)]
        figures["error_before_kill_max_deg"] = max(errors_before)
        figures["error_after_kill_max_deg"] = max(after)
        log(f"failover gap {figures['failover_gap_ms']:.2f} ms (driver receive times); largest error "
            f"{figures['error_before_kill_max_deg']:.2f}° in the second before, "
            f"{figures['error_after_kill_max_deg']:.2f}° after")
        expect(figures["failover_gap_ms"] < 100, f"failover within 100 ms ({figures['failover_gap_ms']:.2f} ms)")
        expect(figures["error_after_kill_max_deg"] < max(5.0, 2 * figures["error_before_kill_max_deg"]),
               "the output stayed locked across the failover")
        bench.wait(lambda: bench.locked_since(killed, window_s=0.5) is not None, 10, "the output to lock under the standby")
        log("ok: locked under the standby")

        # --- network disconnect of the solver → hold; reconnect → resume without a jump --------------
        standby = project.container("controller-standby")
        log(f"docker network disconnect {network} (the standby controller) for {args.disconnect_s} s")
        disconnected = time.monotonic()
        run(["docker", "network", "disconnect", network, standby])
        bench.wait(lambda: (bench.latest_state() or {}).get("mode") == "DRIVER_HOLDING", 10, "the driver to hold")
        holding = bench.latest_state()
        figures["hold_after_disconnect_s"] = time.monotonic() - disconnected
        expect("standby silent" in holding["reason"], f"the driver says why it holds: \"{holding['reason']}\"")
        time.sleep(max(0.0, args.disconnect_s - (time.monotonic() - disconnected)))
        held = [m for _, m in bench.states.snapshot(disconnected) if m["mode"] == "DRIVER_HOLDING"]
        expect(len(held) >= 5 and all(m["phi_applied"] == held[0]["phi_applied"] for m in held),
               f"{len(held)} holding heartbeats, all with the same φ")
        last_sample = max(m["sequence_number"] for _, m in bench.samples.snapshot(disconnected - 0.5))
        reconnect = time.monotonic()
        run(["docker", "network", "connect", "--ip", f"{PREFIX}.21", network, standby])
        bench.wait(lambda: any(m["mode"] == "DRIVER_ACTIVE" and m["obeyed_controller_id"] == "standby"
                               and m["answers_sample"] > last_sample for _, m in bench.states.snapshot(reconnect)),
                   30, "control to resume")
        figures["resume_after_reconnect_s"] = next(
            t for t, m in bench.states.snapshot(reconnect)
            if m["mode"] == "DRIVER_ACTIVE" and m["answers_sample"] > last_sample) - reconnect
        time.sleep(1.0)
        resumed = next(m for _, m in bench.states.snapshot(reconnect)
                       if m["mode"] == "DRIVER_ACTIVE" and m["answers_sample"] > last_sample)
        step = max_abs_difference(resumed["phi_applied"], held[-1]["phi_applied"])
        resume_errors = bench.errors(reconnect)
        at_resume = max((e for t, e in resume_errors if t <= reconnect + figures["resume_after_reconnect_s"]), default=0.0)
        after_resume = max(e for _, e in resume_errors)
        log(f"resumed {figures['resume_after_reconnect_s']:.2f} s after reconnect; first φ step {step:.4f}; "
            f"error {at_resume:.2f}° while holding, at most {after_resume:.2f}° after")
        expect(step < 0.15, f"the first command after the hold continues from the held φ (step {step:.4f})")
        expect(after_resume <= at_resume + 2.0, "no error spike after resuming (no bump at the output)")
        bench.wait(lambda: bench.locked_since(reconnect, window_s=0.5) is not None, 10, "the output to lock again")
        figures["relock_after_reconnect_s"] = bench.locked_since(reconnect, window_s=0.5) - 0.5 - reconnect
        log(f"ok: locked again (a 0.5 s window within 2° began {figures['relock_after_reconnect_s']:.2f} s after the reconnect)")

        # --- SIGTERM: every service ends by itself, cleanly --------------------------------------
        containers = project("ps", "-q").stdout.split()
        stop_started = time.monotonic()
        project("stop", "-t", "10")
        figures["stop_s"] = time.monotonic() - stop_started
        exits = dict(line.split() for line in run(
            ["docker", "inspect", "-f", "{{.Name}} {{.State.ExitCode}}", *containers]).stdout.splitlines())
        log(f"`stop` took {figures['stop_s']:.2f} s; exit codes {exits}")
        unclean = {name: code for name, code in exits.items() if code != "0" and "_controller_" not in name}
        expect(not unclean, f"every service exits 0 on SIGTERM (the killed controller aside): {unclean or 'all'}")
        expect(figures["stop_s"] < 8, f"`stop` did not wait for the 10 s kill timeout ({figures['stop_s']:.2f} s)")
    finally:
        if bench:
            bench.stop()
        log("down")
        down_started = time.monotonic()
        project.down()
        figures["down_s"] = time.monotonic() - down_started
    leftovers = project.leftovers()
    expect(not leftovers, f"`down` left no container, network or volume ({leftovers or 'none'})")
    return figures


def split_deployment(args, base, work):
    figures = {}
    common = {"DPC_NET_PREFIX": SPLIT_PREFIX, "DPC_IMAGE": IMAGE, "DPC_DOMAIN": DOMAIN, "DPC_BENCH_ID": BENCH_ID,
              "DPC_RATE_HZ": str(args.rate_hz), "DPC_SCRAMBLER_RAD_PER_S": str(args.scrambler_rad_per_s)}
    bench_project = Project(base, "dpcsystestbench", ["docker-compose.yml", "deploy/compose/discovery-server.yml"], common)
    solver_project = Project(base, "dpcsystestsolver", ["deploy/compose/solver.yml"], dict(
        common, DPC_LAB_NETWORK=f"dpcsystestbench_bench", DPC_SOLVER_ADDRESS=f"{SPLIT_PREFIX}.40",
        DPC_DDS_SERVER=f"{SPLIT_PREFIX}.2:11811"))
    solver_project.down()
    bench_project.down()
    bench = None
    try:
        log("split: the bench project (discovery server, driver, polarimeter), no controller")
        bench_project("up", "-d", "discovery", "driver", "polarimeter", timeout=300)
        bench = Bench(args.dpc, host_profile(SPLIT_PREFIX, True, work))
        bench.wait(lambda: (bench.latest_state() or {}).get("mode") == "DRIVER_HOLDING", 60,
                   "the driver to report (holding, no controller)")
        log("split: the solver project (one controller, client of the bench's discovery server)")
        up_started = time.monotonic()
        solver_project("up", "-d", timeout=300)
        bench.wait(lambda: bench.locked_since(up_started) is not None, 90, "the solver to lock the output")
        figures["split_up_to_locked_s"] = bench.locked_since(up_started) - up_started
        bench.wait(lambda: bench.latest_state() is not None, 20, "the driver's state")
        state = bench.latest_state()
        expect(state["obeyed_controller_id"] == "remote",
               f"the bench obeys the solver's controller, locked {figures['split_up_to_locked_s']:.2f} s after its `up`")
        down_started = time.monotonic()
        solver_project("down", "-t", "10")
        bench_project("down", "-t", "10")
        figures["split_down_s"] = time.monotonic() - down_started
        expect(figures["split_down_s"] < 16, f"both projects went down without kill timeouts ({figures['split_down_s']:.2f} s)")
    finally:
        if bench:
            bench.stop()
        solver_project.down()
        bench_project.down()
    leftovers = {**solver_project.leftovers(), **bench_project.leftovers()}
    expect(not leftovers, f"both projects left nothing behind ({leftovers or 'none'})")
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--dpc", required=True, help="the host's dpc tool (build/tools/dpc/dpc)")
    parser.add_argument("--rate-hz", type=int, default=2000, help="the polarimeter's rate in the test")
    parser.add_argument("--scrambler-rad-per-s", type=float, default=0.2,
                        help="the input's rotation rate (slow, so that a jump at resume stands out)")
    parser.add_argument("--disconnect-s", type=float, default=1.5, help="how long the solver is cut off")
    parser.add_argument("--cyclone-probe", help="dpc-cyclone-probe: also read the bench with Cyclone DDS")
    parser.add_argument("--skip-split", action="store_true")
    args = parser.parse_args()
    if not os.access(args.dpc, os.X_OK):
        print(f"compose-test: {args.dpc} is not an executable dpc tool", file=sys.stderr)
        return 2

    engine = Engine()
    why = engine.ensure()
    if why:
        print(f"SKIPPED: {why}", flush=True)
        return SKIP
    base = compose_command()
    if base is None:
        if os.geteuid() != 0:
            print("SKIPPED: neither `docker compose` nor `docker-compose` is installed", flush=True)
            return SKIP
        run(["apt-get", "install", "-y", "-qq", "docker-compose"], timeout=900)
        base = compose_command()
    log(f"compose: {' '.join(base)}; engine {run(['docker', 'version', '-f', '{{.Server.Version}}']).stdout.strip()}")
    work = tempfile.mkdtemp(prefix="dpc-compose-test-")
    try:
        run([os.path.join(REPO, "deploy", "make-base-image.sh")], capture=False, timeout=1200)
        figures = failover_and_hold(args, base, work)
        if not args.skip_split:
            figures.update(split_deployment(args, base, work))
        print("FIGURES " + json.dumps({k: round(v, 3) for k, v in figures.items()}), flush=True)
        return 0
    except (Failure, RuntimeError, subprocess.TimeoutExpired) as error:
        print(f"FAILED: {error}", flush=True)
        return 1
    finally:
        shutil.rmtree(work, ignore_errors=True)
        engine.stop()


if __name__ == "__main__":
    sys.exit(main())
