#!/usr/bin/env python3
"""Hardware-in-the-loop runner: the board's cross-compiled test binaries and firmware, run on
the board, with results collected as ctest would.

  tools/hil/run.py <board> <address> [--attached sensor,gpio-loopback,...] [-j N]
                   [--exclude-label long] [--only REGEX] [--skip REGEX] [--remote-prefix CMD]
                   [--binary NAME]... [--ssh-config FILE] [--batch N]

<board> is a folder name under board/; its build.preset names the build (build/<preset>).
<address> is where the board is:
  user@host[:port]   over SSH: the binaries, the firmware and the test data are copied there
                     (scp) into a fresh folder and run there (ssh), results copied back;
  qemu:              the stand-in transport: the same steps on this machine, each binary run
                     under qemu-aarch64 (no board needed).
--remote-prefix runs every binary on the far side through a command (the loopback stand-in's
sshd runs on this x86-64 machine: --remote-prefix qemu-aarch64). --batch N: at most N tests of
a binary share a process (default 16; 1 runs each in its own, as ctest does).

board/<board>/hil.manifest says which tests need which hardware and what a pass means; a test
whose hardware is not --attached is not run and is reported skipped, by name. Exit status 0
when every test run passed.
"""
import argparse
import concurrent.futures
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# What the tests read from the source tree (testing::source_path) besides the binaries.
SOURCE_DATA = ["board", "config", "data", "tests/data", "CMakePresets.json"]


def read_board(board):
    conf = {}
    path = os.path.join(ROOT, "board", board, "board.conf")
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if "=" in line:
                key, value = (s.strip() for s in line.split("=", 1))
                conf[key] = value
    return conf


def read_manifest(board):
    """{test: (hardware, what a pass means)}, {hardware: [VARIABLE=value]}."""
    tests, wiring = {}, {}
    path = os.path.join(ROOT, "board", board, "hil.manifest")
    if not os.path.exists(path):
        return tests, wiring
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            m = re.match(r"test (\S+) needs (\S+): (.+)$", line)
            w = re.match(r"wiring (\S+) (\S+=\S*)$", line)
            if m:
                tests[m.group(1)] = (m.group(2), m.group(3))
            elif w:
                wiring.setdefault(w.group(1), []).append(w.group(2))
            else:
                sys.exit(f"{path}:{number}: not 'test <name> needs <hardware>: ...' or 'wiring ...'")
    return tests, wiring


class LocalQemu:
    """The stand-in transport: a folder on this machine, binaries under qemu-aarch64."""

    def __init__(self, prefix):
        self.prefix = prefix or ["qemu-aarch64"]
        self.root = tempfile.mkdtemp(prefix="rgbdtam_hil_")

    def describe(self):
        return f"this machine under {' '.join(self.prefix)} (stand-in for the board), in {self.root}"

    def mkdir(self, remote):
        os.makedirs(os.path.join(self.root, remote), exist_ok=True)

    def put(self, local, remote):
        target = os.path.join(self.root, remote)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        if os.path.isdir(local):
            shutil.copytree(local, target, dirs_exist_ok=True)
        else:
            shutil.copy2(local, target)

    def run(self, argv, env, timeout):
        full_env = dict(os.environ, **env)
        return subprocess.run(self.prefix + argv, cwd=self.root, env=full_env, timeout=timeout,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def get(self, remote, local):
        shutil.copy2(os.path.join(self.root, remote), local)

    def close(self):
        shutil.rmtree(self.root, ignore_errors=True)


class Ssh:
    """A board over SSH (BatchMode: keys only, never a password prompt)."""

    def __init__(self, address, prefix, options):
        m = re.match(r"^(?:ssh://)?([^@]+@)?([^:/]+)(?::(\d+))?$", address)
        if not m:
            sys.exit(f"hil: '{address}' is not user@host[:port] or qemu:")
        self.target = (m.group(1) or "") + m.group(2)
        self.port = m.group(3) or "22"
        # One connection for every command and copy: each new one costs a key exchange (2.4 s
        # on the loopback check's machine, more on a board's slow cores).
        self.control_dir = tempfile.mkdtemp(prefix="hil_ssh_")
        self.options = ["-o", "BatchMode=yes", "-o", "ConnectTimeout=10",
                        "-o", "ControlMaster=auto",
                        "-o", f"ControlPath={os.path.join(self.control_dir, '%C')}",
                        "-o", "ControlPersist=60"] + options
        self.prefix = prefix
        self.root = self._ssh("mktemp -d /tmp/rgbdtam_hil_XXXXXX").stdout.strip()
        if not self.root:
            shutil.rmtree(self.control_dir, ignore_errors=True)
            sys.exit(f"hil: cannot reach {address} over SSH")

    def describe(self):
        return f"{self.target} port {self.port} over SSH, in {self.root}"

    def _scp(self):
        # -O: the classic scp protocol, which boards without an SFTP server (dropbear) speak.
        return ["scp", "-O", "-q", "-r", "-P", self.port] + self.options

    def _ssh(self, command, timeout=60):
        return subprocess.run(["ssh", "-p", self.port] + self.options + [self.target, command],
                              timeout=timeout, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True)

    def mkdir(self, remote):
        self._ssh(f"mkdir -p {shlex.quote(os.path.join(self.root, remote))}")

    def put(self, local, remote):
        self.mkdir(os.path.dirname(remote))
        subprocess.run(self._scp() + [local, f"{self.target}:{os.path.join(self.root, remote)}"],
                       check=True)

    def run(self, argv, env, timeout):
        assignments = " ".join(f"{k}={shlex.quote(v)}" for k, v in env.items())
        command = f"cd {shlex.quote(self.root)} && env {assignments} " + \
            " ".join(shlex.quote(a) for a in self.prefix + argv)
        return self._ssh(command, timeout)

    def get(self, remote, local):
        subprocess.run(self._scp() + [f"{self.target}:{os.path.join(self.root, remote)}", local],
                       check=True)

    def close(self):
        self._ssh(f"rm -rf {shlex.quote(self.root)}")
        subprocess.run(["ssh", "-p", self.port] + self.options + ["-O", "exit", self.target],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        shutil.rmtree(self.control_dir, ignore_errors=True)


def output_of(test, output):
    """One test's part of a batch's output (GoogleTest's RUN to OK or FAILED lines)."""
    begin = output.find(f"[ RUN      ] {test}\n")
    if begin < 0:
        return output
    end = output.find("\n[ RUN      ] ", begin + 1)
    return output[begin:] if end < 0 else output[begin:end + 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("board")
    parser.add_argument("address")
    parser.add_argument("--attached", default="", help="hardware the rack provides, comma-separated")
    parser.add_argument("--exclude-label", action="append", default=[])
    parser.add_argument("--only", default="", help="run only tests whose name matches")
    parser.add_argument("--skip", default="", help="leave out tests whose name matches")
    parser.add_argument("--binary", action="append", default=[],
                        help="copy and run only this test binary (repeatable)")
    parser.add_argument("--remote-prefix", default="", help="command that runs each binary there")
    parser.add_argument("--ssh-config", default="", help="an ssh_config file for ssh and scp")
    parser.add_argument("-j", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--batch", type=int, default=16,
                        help="most tests of one binary run in one process (1: ctest's way)")
    parser.add_argument("--timeout", type=int, default=900,
                        help="seconds per process (a test, or a batch of them)")
    parser.add_argument("--results", default="", help="folder for the JUnit XML (default in the build)")
    args = parser.parse_args()

    conf = read_board(args.board)
    preset = conf["build.preset"]
    build = os.path.join(ROOT, "build") if preset == "host-release" else os.path.join(ROOT, "build", preset)
    listing = os.path.join(build, "hil-tests.txt")
    if not os.path.exists(listing):
        sys.exit(f"hil: {listing} is missing: build the board first (cmake --build --preset {preset})")
    binaries, process_per_test = [], set()
    with open(listing) as f:
        for line in f:
            name, label, *flags = line.split()
            if "process-per-test" in flags:
                process_per_test.add(name)
            wanted = not args.binary or name in args.binary
            if wanted and label not in args.exclude_label and os.path.exists(os.path.join(build, "bin", name)):
                binaries.append(name)
    manifest, wiring = read_manifest(args.board)
    attached = [a for a in args.attached.split(",") if a]
    prefix = shlex.split(args.remote_prefix)
    ssh_options = ["-F", args.ssh_config] if args.ssh_config else []
    transport = LocalQemu(prefix) if args.address == "qemu:" else Ssh(args.address, prefix, ssh_options)
    results_dir = args.results or os.path.join(build, "hil-results")
    os.makedirs(results_dir, exist_ok=True)
    print(f"hil: board {args.board} ({os.path.relpath(build, ROOT)}), on {transport.describe()}; "
          f"attached: {', '.join(attached) or 'nothing'}")

    started = time.time()
    for name in binaries + ["rgbdtam"]:
        transport.put(os.path.join(build, "bin", name), f"bin/{name}")
    for folder in SOURCE_DATA:
        if os.path.exists(os.path.join(ROOT, folder)):
            transport.put(os.path.join(ROOT, folder), f"source/{folder}")
    print(f"hil: copied {len(binaries)} test binaries, the firmware and the test data in "
          f"{time.time() - started:.1f} s")

    env = {"RGBDTAM_SOURCE_DIR": os.path.join(transport.root, "source"),
           "RGBDTAM_HIL_BOARD": os.path.join(transport.root, "source", "board", args.board),
           "RGBDTAM_HIL_ATTACHED": ",".join(attached),
           "RGBDTAM_TUM_FR1_XYZ": "/nonexistent"}  # the full sequence stays on the host
    for hardware in attached:
        for assignment in wiring.get(hardware, []):
            key, value = assignment.split("=", 1)
            env[key] = value

    # The firmware itself first: it must start, and hold the board's sensor backend.
    firmware = transport.run(["bin/rgbdtam", "check", "--board", f"source/board/{args.board}"],
                             env, 120)
    print(f"hil: firmware: {firmware.stdout.strip()}")
    firmware_ok = firmware.returncode == 0

    # Every test of every binary.
    tests, skipped = [], []
    for name in binaries:
        listed = transport.run([f"bin/{name}", "--gtest_list_tests"], env, 300)
        if listed.returncode != 0:
            print(f"hil: {name} --gtest_list_tests failed:\n{listed.stdout}")
            return 1
        suite = None
        for line in listed.stdout.splitlines():
            if not line.strip() or line.startswith("Running main()"):
                continue
            if not line.startswith(" "):
                suite = line.strip()
                continue
            test = suite + line.split("#", 1)[0].strip()
            if args.only and not re.search(args.only, test):
                continue
            if args.skip and re.search(args.skip, test):
                continue
            if test in manifest and manifest[test][0] not in attached:
                skipped.append((test, manifest[test]))
                continue
            tests.append((name, test))

    # A binary's tests run in batches, a process each (ctest runs a process a test): a process's
    # start and the emulator's translation of its code cost a fifth of a second a test under
    # qemu, more than most tests. A batch that does not end normally (a crash, a timeout) leaves
    # no results: its tests run again one process each, so the one at fault is named. A
    # binary marked process-per-test in hil-tests.txt has batches of one.
    def run_batch(item):
        index, batch = item
        binary = batch[0][1]
        xml_remote = f"results/{index}.xml"
        t0 = time.time()
        try:
            r = transport.run([f"bin/{binary}", "--gtest_filter=" + ":".join(t for _, _, t in batch),
                               f"--gtest_output=xml:{xml_remote}"], env, args.timeout)
            output, code = r.stdout, r.returncode
        except subprocess.TimeoutExpired:
            output, code = f"timed out after {args.timeout} s", -1
        seconds = time.time() - t0
        local_xml = os.path.join(results_dir, f"{index}.xml")
        cases = {}
        try:
            transport.get(xml_remote, local_xml)
            for case in ET.parse(local_xml).getroot().iter("testcase"):
                cases[f"{case.get('classname')}.{case.get('name')}"] = case
        except (OSError, subprocess.CalledProcessError, ET.ParseError):
            pass
        # A failed exit that no test's failure explains (a crash at exit, say) counts as none.
        if code != 0 and not any(c.find("failure") is not None for c in cases.values()):
            cases = {}
        results = []
        for test_index, _, test in batch:
            case = cases.get(test)
            if case is None:
                if len(batch) == 1:
                    results.append((test_index, test, "Failed", seconds, output))
                else:
                    results += run_batch((f"{index}-{test_index}", [(test_index, binary, test)]))
                continue
            status = "Failed"
            if case.get("result") == "skipped":
                status = "Skipped"
            elif case.find("failure") is None:
                status = "Passed"
            results.append((test_index, test, status, float(case.get("time", "0")),
                            output_of(test, output)))
        return results

    batches = []
    for binary in binaries:
        mine = [(i, b, t) for i, (b, t) in enumerate(tests, 1) if b == binary]
        size = max(1, min(args.batch, -(-len(mine) // max(1, args.j))))
        if binary in process_per_test:
            size = 1
        batches += [mine[k:k + size] for k in range(0, len(mine), size)]
    transport.mkdir("results")
    failed, passed, skipped_by_test = [], 0, []
    total = len(tests)
    width = max([len(t) for _, t in tests] + [10])
    done = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.j)) as pool:
        for results in pool.map(run_batch, enumerate(batches, 1)):
            for index, test, status, seconds, output in results:
                done += 1
                print(f"{done:3}/{total} Test #{index}: {test} {'.' * (width + 3 - len(test))} "
                      f"{status:>8} {seconds:7.2f} sec", flush=True)
                if status == "Passed":
                    passed += 1
                elif status == "Skipped":
                    skipped_by_test.append(test)
                else:
                    failed.append(test)
                    print(output[-4000:])
    transport.close()

    if firmware_ok:
        passed += 1
    else:
        failed.append("BoardBuild.TheBoardsSensorIsInThisBuild (rgbdtam check)")
    ran = passed + len(failed)
    print(f"\n{100 * passed // max(ran, 1)}% tests passed, {len(failed)} tests failed out of {ran} "
          f"run on the board ({time.time() - started:.0f} s)")
    if skipped:
        print(f"\nNot run: hardware not attached ({len(skipped)}, board/{args.board}/hil.manifest):")
        for test, (hardware, meaning) in skipped:
            print(f"  {test}  needs {hardware}: {meaning}")
    if skipped_by_test:
        print(f"\nSkipped by the test itself ({len(skipped_by_test)}):")
        for test in skipped_by_test:
            print(f"  {test}")
    if failed:
        print("\nThe following tests FAILED:")
        for test in failed:
            print(f"  {test}")
        return 1
    return 0 if ran > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
