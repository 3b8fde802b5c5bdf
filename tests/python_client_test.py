#!/usr/bin/env python3
"""The Python client (clients/python/farm_client.py over the code generated from
proto/farm.proto) against a real farm-coordinator and farm-worker, secured with TLS and tokens:
it submits a scene, watches the job to its end, fetches the image and reads it back, without the
farm CLI; a token of the wrong role is refused with PERMISSION_DENIED.

Run by ctest with FARM_COORDINATOR_BIN, FARM_WORKER_BIN, FARM_CLI_BIN and FARM_SHARED_DIR set,
and build/python and clients/python on PYTHONPATH."""

import os
import re
import shutil
import subprocess
import tempfile
import time
import unittest

import grpc
import numpy
import OpenImageIO as oiio

from farm_client import FarmClient, FarmError, farm_pb2

COORDINATOR = os.environ["FARM_COORDINATOR_BIN"]
WORKER = os.environ["FARM_WORKER_BIN"]
CLI = os.environ["FARM_CLI_BIN"]
SCENE = os.path.join(os.environ["FARM_SHARED_DIR"], "scenes", "cornell-box", "scene.xml")


def openssl(*args, cwd):
    subprocess.run(["openssl", *args], cwd=cwd, check=True, capture_output=True)


def make_pki(d):
    """A CA and a server certificate it signs for localhost and 127.0.0.1."""
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", "ca.key", "-out",
            "ca.pem", "-days", "2", "-subj", "/CN=python test CA", cwd=d)
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", "server.key", "-out",
            "server.csr", "-subj", "/CN=localhost", cwd=d)
    with open(os.path.join(d, "san.ext"), "w") as f:
        f.write("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    openssl("x509", "-req", "-in", "server.csr", "-CA", "ca.pem", "-CAkey", "ca.key",
            "-CAcreateserial", "-out", "server.pem", "-days", "2", "-extfile", "san.ext", cwd=d)
    for role in ("submit", "work"):
        with open(os.path.join(d, role + ".token"), "w") as f:
            f.write(role + "-token-" + os.urandom(16).hex() + "\n")


class PythonClientTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="farm-python-client-")
        self.processes = []
        make_pki(self.dir)
        at = lambda name: os.path.join(self.dir, name)
        log = open(at("coordinator.out"), "w")
        self.processes.append(subprocess.Popen(
            [COORDINATOR, "--listen", "127.0.0.1:0", "--tls-cert", at("server.pem"), "--tls-key",
             at("server.key"), "--submit-token-file", at("submit.token"), "--work-token-file",
             at("work.token")], stdout=log, stderr=subprocess.STDOUT))
        port = None
        for _ in range(150):
            match = re.search(r"listening on 127\.0\.0\.1:(\d+)", open(at("coordinator.out")).read())
            if match:
                port = match.group(1)
                break
            time.sleep(0.1)
        self.assertIsNotNone(port, open(at("coordinator.out")).read())
        self.address = "localhost:" + port
        self.processes.append(subprocess.Popen(
            [WORKER, "--coordinator", self.address, "--threads", "2", "--cache", at("cache"),
             "--tls-ca", at("ca.pem"), "--token-file", at("work.token")],
            stdout=open(at("worker.log"), "w"), stderr=subprocess.STDOUT))
        self.at = at

    def tearDown(self):
        for p in reversed(self.processes):
            p.terminate()
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_submit_watch_fetch(self):
        client = FarmClient(self.address, ca=self.at("ca.pem"), token_file=self.at("submit.token"))
        job = client.submit(SCENE, algorithm="pssmlt", width=48, height=32, mpp=64, seed=7,
                            combine_large_steps=True)
        self.assertTrue(job.startswith("job-"), job)

        messages = list(client.watch(job, interval=0.2))
        self.assertGreaterEqual(len(messages), 2)
        self.assertEqual(messages[-1].phase, farm_pb2.DONE, messages[-1].error)
        # Kelemen's combination reached the job: its large steps are not pooled into Z.
        self.assertTrue(messages[-1].settings.combine_large_steps)
        self.assertEqual(messages[-1].large_steps, 0)
        fractions = [m.fraction for m in messages]
        self.assertEqual(fractions, sorted(fractions))
        self.assertEqual(sum(len(m.error_series) for m in messages),
                         messages[-1].error_series_total)

        out = self.at("python.exr")
        client.fetch(job, out)
        image = oiio.ImageBuf(out)
        self.assertEqual((image.spec().width, image.spec().height), (48, 32))
        pixels = image.get_pixels(oiio.FLOAT)
        self.assertTrue(numpy.isfinite(pixels).all())
        self.assertGreater(pixels.mean(), 0.0)

        # The C++ CLI sees the same job done.
        status = subprocess.run([CLI, "status", "--coordinator", self.address, "--tls-ca",
                                 self.at("ca.pem"), "--token-file", self.at("submit.token"), job],
                                capture_output=True, text=True, timeout=60)
        self.assertEqual(status.returncode, 0, status.stderr)
        self.assertIn("done", status.stdout)

    def test_auto_is_the_default_and_pilot_needs_it(self):
        client = FarmClient(self.address, ca=self.at("ca.pem"), token_file=self.at("submit.token"))
        with self.assertRaises(ValueError):
            client.submit(SCENE, algorithm="pt", pilot=True)
        job = client.submit(SCENE, width=32, height=24, spp=4, seed=3)
        messages = list(client.watch(job, interval=0.2))
        self.assertEqual(messages[-1].phase, farm_pb2.DONE, messages[-1].error)
        plan = [line for m in messages for line in m.render_plan]
        # The Cornell box: no specular surface, the light in sight, so the plan renders pt.
        self.assertIn("algorithm: pt (auto)", "\n".join(plan))
        summary = [j for j in client.list() if j.job_id == job]
        self.assertEqual([j.algorithm for j in summary], [farm_pb2.PT])

    def test_the_work_token_does_not_open_the_client_api(self):
        client = FarmClient(self.address, ca=self.at("ca.pem"), token_file=self.at("work.token"))
        with self.assertRaises(FarmError) as caught:
            client.list()
        self.assertEqual(caught.exception.code, grpc.StatusCode.PERMISSION_DENIED)
        anonymous = FarmClient(self.address, ca=self.at("ca.pem"))
        with self.assertRaises(FarmError) as caught:
            anonymous.submit(SCENE)
        self.assertEqual(caught.exception.code, grpc.StatusCode.UNAUTHENTICATED)


if __name__ == "__main__":
    unittest.main()
