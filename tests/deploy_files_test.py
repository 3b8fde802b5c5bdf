#!/usr/bin/env python3
"""deploy/ against the binaries and the Kubernetes schemas.

Every flag that the Dockerfile, the Kubernetes manifests, the systemd units and the Slurm
script pass to farm-coordinator, farm-worker or farm must be one that program's --help lists
(a renamed flag would otherwise break a deployment, not a build). The image's runtime stage
must install every library the programs load. The manifests must validate against the
Kubernetes API's schemas (the kubernetes-models npm package that deploy/install-deps.sh
installs under deploy/.npm; there is no cluster here to ask).

Run by ctest with FARM_COORDINATOR_BIN, FARM_WORKER_BIN, FARM_CLI_BIN and FARM_SOURCE_DIR set."""

import functools
import glob
import json
import os
import re
import shlex
import subprocess
import unittest

import yaml

SOURCE = os.environ["FARM_SOURCE_DIR"]
DEPLOY = os.path.join(SOURCE, "deploy")
BINARIES = {
    "farm-coordinator": os.environ["FARM_COORDINATOR_BIN"],
    "farm-worker": os.environ["FARM_WORKER_BIN"],
    "farm": os.environ["FARM_CLI_BIN"],
}


def joined_lines(path):
    """The file's lines with backslash continuations joined."""
    with open(path) as f:
        return f.read().replace("\\\n", " ").splitlines()


def invocations():
    """(file, argv) for every command line in deploy/ that runs one of the farm's programs."""
    found = []
    dockerfile = os.path.join(DEPLOY, "Dockerfile")
    for line in joined_lines(dockerfile):
        m = re.match(r"\s*(CMD|ENTRYPOINT)\s+(\[.*\])\s*$", line)
        if m:
            found.append((dockerfile, json.loads(m.group(2))))
    for path in sorted(glob.glob(os.path.join(DEPLOY, "kubernetes", "*.yaml"))):
        with open(path) as f:
            for doc in yaml.safe_load_all(f):
                spec = (doc or {}).get("spec", {}).get("template", {}).get("spec", {})
                for container in spec.get("containers", []):
                    found.append((path, container.get("command", []) + container.get("args", [])))
    for path in sorted(glob.glob(os.path.join(DEPLOY, "systemd", "*.service"))):
        for line in joined_lines(path):
            if line.startswith("ExecStart="):
                found.append((path, shlex.split(line[len("ExecStart="):])))
    for path in sorted(glob.glob(os.path.join(DEPLOY, "slurm", "*"))):
        for line in joined_lines(path):
            if line.lstrip().startswith("srun "):
                argv = shlex.split(line)
                programs = [i for i, a in enumerate(argv) if os.path.basename(a) in BINARIES]
                if programs:
                    found.append((path, argv[programs[0]:]))
    return found


def help_text(program, subcommand=None):
    argv = [BINARIES[program]] + ([subcommand] if subcommand else []) + ["--help"]
    result = subprocess.run(argv, capture_output=True, text=True, timeout=30)
    return result.stdout + result.stderr


# In debian:12-slim already: what dpkg and apt themselves load (libc6, libgcc-s1, libstdc++6,
# zlib1g), so the Dockerfile need not name them.
SLIM_BASE = {"libc6", "libgcc-s1", "libstdc++6", "zlib1g"}


def runtime_packages():
    """The packages the Dockerfile's last stage installs (its last apt-get install)."""
    lines = joined_lines(os.path.join(DEPLOY, "Dockerfile"))
    last_from = max(i for i, line in enumerate(lines) if line.startswith("FROM "))
    for line in lines[last_from:]:
        m = re.search(r"apt-get install ([^&]*)", line)
        if m:
            return {w for w in m.group(1).split() if not w.startswith("-")}
    return set()


@functools.lru_cache(maxsize=None)
def loader_cache():
    """`ldconfig -p`: the libraries the loader knows, read once."""
    return subprocess.run(["ldconfig", "-p"], capture_output=True, text=True).stdout


@functools.lru_cache(maxsize=None)
def package_of_library(soname):
    """The Debian package that holds the shared library the loader finds for `soname`."""
    for line in loader_cache().splitlines():
        parts = line.split()
        if parts and parts[0] == soname and "x86-64" in line:
            path = os.path.realpath(parts[-1])
            owner = subprocess.run(["dpkg", "-S", path], capture_output=True, text=True)
            if owner.returncode != 0:  # merged /usr: dpkg knows the /lib name
                owner = subprocess.run(["dpkg", "-S", path.replace("/usr/lib/", "/lib/", 1)],
                                       capture_output=True, text=True)
            if owner.returncode == 0:
                return owner.stdout.split(":")[0]
    return None


class DeployFilesTest(unittest.TestCase):
    def test_the_image_installs_every_library_the_programs_load(self):
        # The image is not built here (no Docker): this is the check that its runtime stage
        # would start the programs. Every library each binary names (DT_NEEDED; what those load
        # in turn comes with the packages' own dependencies) must come from a package the last
        # stage installs, or one debian:12-slim has.
        installed = runtime_packages()
        self.assertIn("libgrpc++1.51", installed, "the Dockerfile's package list was not found")
        for program, binary in BINARIES.items():
            dynamic = subprocess.run(["readelf", "-d", binary], capture_output=True, text=True,
                                     check=True).stdout
            needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic)
            self.assertGreater(len(needed), 5, program)
            for soname in needed:
                package = package_of_library(soname)
                self.assertIsNotNone(package, f"{program} loads {soname}, which no package holds")
                self.assertIn(package, installed | SLIM_BASE,
                              f"{program} loads {soname} from {package}, which deploy/Dockerfile's "
                              f"runtime stage does not install")

    def test_every_flag_is_accepted_by_its_program(self):
        found = invocations()
        by_file = {}
        for path, argv in found:
            by_file[os.path.relpath(path, DEPLOY)] = by_file.get(os.path.relpath(path, DEPLOY), 0) + 1
        # Each file's command lines were found (a parser that finds none would pass vacuously).
        self.assertEqual(by_file, {
            "Dockerfile": 1,
            "kubernetes/coordinator.yaml": 1,
            "kubernetes/workers.yaml": 1,
            "systemd/farm-coordinator.service": 1,
            "systemd/farm-worker.service": 1,
            "slurm/farm-workers.sbatch": 1,
        })
        helps = {}
        for path, argv in found:
            program = os.path.basename(argv[0])
            self.assertIn(program, BINARIES, f"{path}: runs {argv[0]}")
            subcommand = argv[1] if program == "farm" else None
            key = (program, subcommand)
            if key not in helps:
                helps[key] = help_text(program, subcommand)
            for token in argv[1:]:
                if not token.startswith("--"):
                    continue
                flag = token.split("=", 1)[0]
                # An option's own line in CLI11's help ("  --flag TEXT", "  -o,--output"),
                # not a mention in another option's prose.
                self.assertRegex(helps[key], r"(?m)^\s+(-\w,)?" + re.escape(flag) + r"\b",
                                 f"{os.path.relpath(path, SOURCE)} passes {flag}, which "
                                 f"{program} --help does not list")

    def test_manifests_match_the_kubernetes_schemas(self):
        node_modules = os.path.join(DEPLOY, ".npm", "node_modules")
        self.assertTrue(os.path.isdir(os.path.join(node_modules, "kubernetes-models")),
                        "kubernetes-models is not installed: run deploy/install-deps.sh")
        objects = []
        for path in sorted(glob.glob(os.path.join(DEPLOY, "kubernetes", "*.yaml"))):
            with open(path) as f:
                objects += [doc for doc in yaml.safe_load_all(f) if doc]
        self.assertGreaterEqual(len(objects), 5)
        result = subprocess.run(
            ["node", os.path.join(SOURCE, "tests", "validate_k8s.js")],
            input=json.dumps(objects), capture_output=True, text=True, timeout=120,
            env=dict(os.environ, NODE_PATH=node_modules))
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertEqual(result.stdout.count("valid: "), len(objects), result.stdout)


if __name__ == "__main__":
    unittest.main()
