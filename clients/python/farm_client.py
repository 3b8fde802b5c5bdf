#!/usr/bin/env python3
"""A Python client of the farm's client API (farm.v1.ClientApi), without the `farm` CLI.

The gRPC half is generated from proto/farm.proto at build time (build/python/proto/, by
Debian's grpc_python_plugin); this file adds what a script needs on top: a scene folder
uploaded as a bundle, a watch that yields progress, an image fetched whole or not at all.

    PYTHONPATH=build/python:clients/python python3 -m farm_client \\
        --coordinator 127.0.0.1:50051 submit SCENE.xml --width 256 --height 256
    ... watch JOB          ... fetch JOB -o out.exr          ... cancel JOB

or from Python:

    from farm_client import FarmClient
    client = FarmClient("127.0.0.1:50051", ca="ca.pem", token_file="submit.token")
    job = client.submit("scene/scene.xml", algorithm="mlt", width=256, height=256, mpp=64)
    for progress in client.watch(job):
        print(progress.phase, progress.fraction)
    client.fetch(job, "out.exr")
"""

import argparse
import hashlib
import os
import sys

import grpc

try:
    from proto import farm_pb2, farm_pb2_grpc
except ImportError as e:  # the generated half is not on the path
    raise ImportError(
        "farm_client needs the generated proto/farm_pb2*.py: build the project and put "
        "build/python on PYTHONPATH (" + str(e) + ")") from e

CHUNK_BYTES = 1 << 20  # as proto/wire_limits.h's kMaxChunkBytes
MAX_MESSAGE_BYTES = 16 << 20  # kMaxMessageBytes
MAX_BUNDLE_FILE_BYTES = 256 << 20  # kMaxBundleFileBytes: larger files are left out

ALGORITHMS = {
    "pt": farm_pb2.PT,
    "bdpt": farm_pb2.BDPT,
    "pssmlt": farm_pb2.PSSMLT,
    "pssmlt-pt": farm_pb2.PSSMLT_PT,
    "mmlt": farm_pb2.MMLT,
    "mlt": farm_pb2.MLT,
    "erpt": farm_pb2.ERPT,
}
# What the coordinator's plan picks when the algorithm is "auto" (the default, as `farm submit`'s):
# the first of its candidates for the scene, or with pilot=True the best of a pilot of each.
AUTO = "auto"
TERMINAL = {farm_pb2.DONE, farm_pb2.FAILED, farm_pb2.CANCELLED}


class FarmError(Exception):
    """A call the coordinator refused or could not answer; `code` is the gRPC status code."""

    def __init__(self, code, message):
        super().__init__(f"{code.name}: {message}")
        self.code = code


def phase_name(phase):
    return farm_pb2.JobPhase.Name(phase).lower().replace("_", " ")


def _sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(CHUNK_BYTES), b""):
            digest.update(block)
    return digest.hexdigest()


def collect_bundle(scene_file):
    """The scene's folder as (root, manifest entries, local paths), as `farm submit` collects
    it: every file inside, by SHA-256; links that lead out of the folder and files over
    256 MiB left out (a warning on stderr for each)."""
    if not os.path.isfile(scene_file):
        raise FarmError(grpc.StatusCode.INVALID_ARGUMENT,
                        f"scene file '{scene_file}' does not exist")
    root = os.path.dirname(os.path.abspath(scene_file))
    real_root = os.path.realpath(root)
    files = []
    for folder, _, names in os.walk(root):
        for name in names:
            files.append(os.path.join(folder, name))
    entries, local = [], []
    for path in sorted(files):
        relative = os.path.relpath(path, root).replace(os.sep, "/")
        if os.path.islink(path):
            target = os.path.realpath(path)
            if os.path.commonpath([target, real_root]) != real_root:
                print(f"farm_client: leaving out '{relative}': a symbolic link to '{target}', "
                      "outside the scene's folder", file=sys.stderr)
                continue
        if not os.path.isfile(path):
            continue
        size = os.path.getsize(path)
        if size > MAX_BUNDLE_FILE_BYTES:
            print(f"farm_client: leaving out '{relative}' ({size >> 20} MiB, over the 256 MiB "
                  "limit for bundle files)", file=sys.stderr)
            continue
        entries.append(farm_pb2.BundleFile(path=relative, size=size, hash=_sha256(path)))
        local.append(path)
    return root, entries, local


class FarmClient:
    """The client API of one coordinator. `ca` (PEM roots) selects TLS; `cert` and `key` a
    client certificate for a coordinator that asks for one; `token_file` the submit token."""

    def __init__(self, address, ca=None, cert=None, key=None, token_file=None):
        self.address = address
        options = [("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
                   ("grpc.max_send_message_length", MAX_MESSAGE_BYTES)]
        if ca:
            def read(path):
                with open(path, "rb") as f:
                    return f.read()
            credentials = grpc.ssl_channel_credentials(
                root_certificates=read(ca),
                private_key=read(key) if key else None,
                certificate_chain=read(cert) if cert else None)
            self.channel = grpc.secure_channel(address, credentials, options=options)
        else:
            if cert or key:
                raise ValueError("a client certificate needs TLS: give the coordinator's CA too")
            self.channel = grpc.insecure_channel(address, options=options)
        self.metadata = ()
        if token_file:
            with open(token_file, encoding="ascii") as f:
                token = f.readline().strip()
            if not token:
                raise ValueError(f"token file '{token_file}' holds no token on its first line")
            self.metadata = (("authorization", "Bearer " + token),)
        self.stub = farm_pb2_grpc.ClientApiStub(self.channel)

    def _call(self, method, request, timeout=15):
        try:
            return method(request, timeout=timeout, metadata=self.metadata)
        except grpc.RpcError as e:
            raise FarmError(e.code(), e.details()) from None

    def submit(self, scene_file, algorithm=AUTO, width=0, height=0, spp=16, mpp=16,
               seed=1, time=0.0, chains=0, large_step=0.3, name=None, reference=None,
               pilot=False, combine_large_steps=False):
        """Uploads what the coordinator lacks of the scene's folder and starts a job; returns
        its id. algorithm "auto" lets the coordinator's plan choose (with pilot=True, a pilot of
        its candidates). combine_large_steps weights pssmlt's, pssmlt-pt's and mmlt's large steps
        into the chain (Kelemen et al. 2002, 4.1). Settings the arguments do not name keep the
        coordinator's defaults."""
        automatic = algorithm == AUTO
        if not automatic and algorithm not in ALGORITHMS:
            raise ValueError(f"unknown algorithm '{algorithm}' "
                             f"(one of {AUTO}, {', '.join(ALGORITHMS)})")
        if pilot and not automatic:
            raise ValueError("pilot=True needs algorithm 'auto': the pilot ranks the plan's "
                             "candidates")
        root, entries, local = collect_bundle(scene_file)
        scene_path = os.path.relpath(os.path.abspath(scene_file), root).replace(os.sep, "/")
        settings = farm_pb2.RenderSettings(
            algorithm=ALGORITHMS.get(algorithm, farm_pb2.PSSMLT), auto_algorithm=automatic,
            pilot=pilot, width=width, height=height, samples_per_pixel=spp,
            mutations_per_pixel=mpp, seed=seed, time_budget_seconds=time, num_chains=chains,
            large_step_probability=large_step, combine_large_steps=combine_large_steps)
        header = farm_pb2.JobHeader(
            settings=settings, manifest=farm_pb2.BundleManifest(files=entries),
            scene_path=scene_path, name=name or os.path.basename(scene_file))
        by_hash = {e.hash: p for e, p in zip(entries, local)}
        if reference:
            digest = _sha256(reference)
            header.reference.CopyFrom(farm_pb2.BundleFile(
                path="reference.exr", size=os.path.getsize(reference), hash=digest))
            by_hash[digest] = reference
        missing = self._call(self.stub.MissingBlobs,
                             farm_pb2.MissingBlobsRequest(hashes=sorted(by_hash))).missing_hashes

        def requests():
            yield farm_pb2.SubmitJobRequest(header=header)
            for digest in missing:
                offset = 0
                with open(by_hash[digest], "rb") as f:
                    for block in iter(lambda: f.read(CHUNK_BYTES), b""):
                        yield farm_pb2.SubmitJobRequest(chunk=farm_pb2.BlobChunk(
                            hash=digest, offset=offset, data=block))
                        offset += len(block)

        response = self._call(self.stub.SubmitJob, requests(), timeout=1800)
        return response.job_id

    def progress(self, job_id):
        return self._call(self.stub.GetProgress, farm_pb2.GetProgressRequest(job_id=job_id))

    def watch(self, job_id, interval=0.5):
        """Yields the job's progress (farm_pb2.JobProgress) every `interval` seconds until it
        ends; each message's error_series holds only the samples not yielded before."""
        request = farm_pb2.WatchJobRequest(job_id=job_id, interval_ms=int(interval * 1000))
        try:
            for progress in self.stub.WatchJob(request, metadata=self.metadata):
                yield progress
        except grpc.RpcError as e:
            raise FarmError(e.code(), e.details()) from None

    def fetch(self, job_id, path, wait=True):
        """Writes the job's EXR to `path` (beside, then renamed: a failure leaves no file)."""
        partial = path + ".partial"
        received, total = 0, None
        try:
            with open(partial, "wb") as out:
                request = farm_pb2.FetchImageRequest(job_id=job_id, wait=wait)
                for chunk in self.stub.FetchImage(request, timeout=1800,
                                                  metadata=self.metadata):
                    if chunk.offset != received:
                        raise FarmError(grpc.StatusCode.DATA_LOSS, "image chunks out of order")
                    out.write(chunk.data)
                    received += len(chunk.data)
                    total = chunk.total_size
            if total is None or received != total:
                raise FarmError(grpc.StatusCode.DATA_LOSS,
                                f"the image arrived incomplete ({received} of {total} bytes)")
            os.replace(partial, path)
        except grpc.RpcError as e:
            raise FarmError(e.code(), e.details()) from None
        finally:
            if os.path.exists(partial):
                os.remove(partial)

    def cancel(self, job_id):
        return self._call(self.stub.CancelJob, farm_pb2.CancelJobRequest(job_id=job_id)).phase

    def list(self):
        return list(self._call(self.stub.ListJobs, farm_pb2.ListJobsRequest()).jobs)


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="farm_client", description="Submit, watch, fetch and cancel farm jobs from Python.")
    parser.add_argument("--coordinator", required=True, help="HOST:PORT of the farm-coordinator")
    parser.add_argument("--tls-ca", help="PEM roots to verify the coordinator against (TLS)")
    parser.add_argument("--tls-cert", help="PEM client certificate (mutual TLS)")
    parser.add_argument("--tls-key", help="PEM private key of --tls-cert")
    parser.add_argument("--token-file", help="file whose first line is the submit token")
    commands = parser.add_subparsers(dest="command", required=True)
    submit = commands.add_parser("submit", help="upload SCENE's folder and start a job")
    submit.add_argument("scene")
    submit.add_argument("--algorithm", default=AUTO, choices=[AUTO] + sorted(ALGORITHMS),
                        help="auto (the default) lets the coordinator's plan choose")
    submit.add_argument("--pilot", action="store_true",
                        help="with auto: a pilot of the plan's candidates picks")
    submit.add_argument("--width", type=int, default=0)
    submit.add_argument("--height", type=int, default=0)
    submit.add_argument("--spp", type=int, default=16)
    submit.add_argument("--mpp", type=int, default=16)
    submit.add_argument("--seed", type=int, default=1)
    submit.add_argument("--time", type=float, default=0.0)
    submit.add_argument("--reference")
    watch = commands.add_parser("watch", help="print the job's progress until it ends")
    watch.add_argument("job")
    watch.add_argument("--interval", type=float, default=0.5)
    fetch = commands.add_parser("fetch", help="wait for the job and download its EXR")
    fetch.add_argument("job")
    fetch.add_argument("-o", "--output", required=True)
    cancel = commands.add_parser("cancel", help="cancel a job")
    cancel.add_argument("job")
    commands.add_parser("list", help="list the coordinator's jobs")
    args = parser.parse_args(argv)

    client = FarmClient(args.coordinator, ca=args.tls_ca, cert=args.tls_cert, key=args.tls_key,
                        token_file=args.token_file)
    try:
        if args.command == "submit":
            print(client.submit(args.scene, algorithm=args.algorithm, width=args.width,
                                height=args.height, spp=args.spp, mpp=args.mpp, seed=args.seed,
                                time=args.time, reference=args.reference, pilot=args.pilot))
        elif args.command == "watch":
            last = None
            for p in client.watch(args.job, args.interval):
                estimate = [e.estimated_relmse for e in p.error_series if e.estimated_relmse >= 0]
                print(f"{phase_name(p.phase):13s} {100 * p.fraction:5.1f}%  "
                      f"{p.samples_per_second:10.0f} samples/s  ETA {p.eta_seconds:6.1f} s  "
                      f"{p.active_workers} worker(s)"
                      + (f"  est. relMSE {estimate[-1]:.4g}" if estimate else ""), flush=True)
                last = p
            if last is None or last.phase != farm_pb2.DONE:
                print(f"farm_client: job {args.job} ended "
                      f"{phase_name(last.phase) if last else 'unseen'}"
                      + (f": {last.error}" if last and last.error else ""), file=sys.stderr)
                return 1
        elif args.command == "fetch":
            client.fetch(args.job, args.output)
            print(f"wrote {args.output}")
        elif args.command == "cancel":
            print(f"job {args.job}: {phase_name(client.cancel(args.job))}")
        elif args.command == "list":
            for j in client.list():
                print(f"{j.job_id:20s} {phase_name(j.phase):13s} {100 * j.fraction:5.1f}%  {j.name}")
    except FarmError as e:
        print(f"farm_client: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
