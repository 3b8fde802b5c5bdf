#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora (fuzz/corpus/<target>/): malformed and hostile inputs
of the kinds a coordinator meets - truncated uploads, wrong checksums, unknown job ids, flushes
of the wrong size, NaN and negative splats, hostile paths, broken scene files - and a few
well-formed ones for the fuzzer to mutate from. Deterministic: run it again and nothing changes.

    PYTHONPATH=build/python /usr/bin/python3 tools/make_fuzz_corpus.py
"""

import hashlib
import os
import re
import struct

from proto import farm_pb2 as pb

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
CORPUS = os.path.join(ROOT, "fuzz", "corpus")
# The coordinator's protocol (proto/wire_limits.h), so that hostile registrations get past it.
PROTOCOL_VERSION = int(re.search(r"kProtocolVersion = (\d+);",
                                 open(os.path.join(ROOT, "proto", "wire_limits.h")).read()).group(1))
SHARED = os.path.join(ROOT, "..", "shared")


def write(target, name, data):
    folder = os.path.join(CORPUS, target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def sha(data):
    return hashlib.sha256(data).hexdigest()


# --- scene_loader: first byte 0 Mitsuba XML, 1 pbrt, 2 OBJ, 3 PLY --------------------------
cornell = read(os.path.join(SHARED, "scenes", "cornell-box", "scene.xml"))
scenes = {
    "xml-cornell": b"\0" + cornell,
    "xml-truncated": b"\0" + cornell[: len(cornell) // 2],
    "xml-empty": b"\0",
    "xml-not-xml": b"\0\xff\xfe<<<>>>&&&",
    "xml-nan-radiance": b"\0<scene version=\"0.6.0\"><shape type=\"rectangle\"><emitter type=\"area\">"
                        b"<rgb name=\"radiance\" value=\"nan, inf, -1\"/></emitter></shape></scene>",
    "xml-huge-film": b"\0<scene version=\"0.6.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\">"
                     b"<integer name=\"width\" value=\"2147483647\"/><integer name=\"height\" "
                     b"value=\"-5\"/></film></sensor></scene>",
    "xml-escaping-mesh": b"\0<scene version=\"0.6.0\"><shape type=\"obj\"><string name=\"filename\" "
                         b"value=\"../../../../etc/passwd\"/></shape></scene>",
    "xml-absolute-mesh": b"\0<scene version=\"0.6.0\"><shape type=\"ply\"><string name=\"filename\" "
                         b"value=\"/dev/zero\"/></shape></scene>",
    "xml-deep-nesting": b"\0" + b"<scene version=\"0.6.0\">" + b"<bsdf type=\"twosided\">" * 2000,
    "xml-matrix-singular": b"\0<scene version=\"0.6.0\"><shape type=\"sphere\"><transform name=\"toWorld\">"
                           b"<matrix value=\"0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\"/></transform></shape></scene>",
    "pbrt-minimal": b"\x01LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\" \"float fov\" [45]\n"
                    b"Film \"rgb\" \"integer xresolution\" [8] \"integer yresolution\" [8]\n"
                    b"WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                    b"Shape \"sphere\" \"float radius\" [1]\nAttributeEnd\n",
    "pbrt-unterminated-string": b"\x01Camera \"perspective",
    "pbrt-import-loop": b"\x01Import \"scene.pbrt\"\n",
    "pbrt-include-outside": b"\x01Include \"/etc/passwd\"\n",
    "pbrt-bad-mesh-indices": b"\x01WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 99999999 -1]"
                             b" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n",
    "pbrt-nan-transform": b"\x01Translate nan inf -inf\nWorldBegin\n",
    "obj-triangle": b"\x02v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "obj-bad-indices": b"\x02v 0 0 0\nf 1 2 99999\nf -7 0 1\n",
    "obj-nan-vertices": b"\x02v nan 0 0\nv inf 1 0\nv 0 -inf 0\nf 1 2 3\n",
    "obj-empty": b"\x02",
    "ply-ascii": b"\x03ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                 b"end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    "ply-empty-face-row": b"\x03ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                          b"property float y\nproperty float z\nelement face 2\n"
                          b"property list uchar int vertex_indices\nend_header\n"
                          b"0 0 0\n1 0 0\n0 1 0\n0\n3 0 1 2\n",
    "ply-absurd-counts": b"\x03ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                         b"property float x\nend_header\n\0\0\0\0",
    "ply-truncated-binary": b"\x03ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                            b"property float y\nproperty float z\nelement face 1\n"
                            b"property list uchar int vertex_indices\nend_header\n\0\0\x80?",
}
for name, data in scenes.items():
    write("scene_loader", name, data)


# --- bundle_manifest: a BundleManifest message --------------------------------------------
def manifest(*files):
    return pb.BundleManifest(files=[pb.BundleFile(path=p, size=s, hash=h) for p, s, h in files])


good_hash = sha(b"scene")
manifests = {
    "valid": manifest(("scene.xml", 5, good_hash), ("meshes/a.obj", 10, sha(b"a"))),
    "parent": manifest(("../escape.xml", 1, good_hash)),
    "deep-parent": manifest(("a/b/../../../c", 1, good_hash)),
    "absolute": manifest(("/etc/passwd", 1, good_hash)),
    "backslash": manifest(("..\\windows", 1, good_hash)),
    "nul": manifest(("scene.xml\0.png", 1, good_hash)),
    "dot": manifest(("./scene.xml", 1, good_hash)),
    "empty-component": manifest(("a//b", 1, good_hash)),
    "duplicate": manifest(("scene.xml", 5, good_hash), ("scene.xml", 5, good_hash)),
    "bad-hash": manifest(("scene.xml", 5, "not-a-hash")),
    "uppercase-hash": manifest(("scene.xml", 5, good_hash.upper())),
    "huge-size": manifest(("scene.xml", 2**63, good_hash)),
    "empty-path": manifest(("", 0, good_hash)),
}
for name, m in manifests.items():
    write("bundle_manifest", name, m.SerializeToString())
write("bundle_manifest", "not-protobuf", b"\xff\xff\xff\xff../../etc")


# --- requests: first byte the method (fuzz/fuzz_requests.cpp), then the request ------------
MISSING, SUBMIT, PROGRESS, FETCH, CANCEL, LIST, WATCH, REGISTER, LEASE, RENEW, BUNDLE, UPLOAD = range(12)


def stream(*messages):
    out = b""
    for m in messages:
        data = m.SerializeToString()
        out += struct.pack("<H", min(len(data), 0xFFFF)) + data[:0xFFFF]
    return out


def request(method, body):
    return bytes([method]) + body


settings = pb.RenderSettings(algorithm=pb.PT, width=8, height=8, samples_per_pixel=1, seed=1)
scene_bytes = cornell
header = pb.JobHeader(settings=settings, scene_path="scene.xml",
                      manifest=manifest(("scene.xml", len(scene_bytes), sha(scene_bytes))))
chunk = pb.BlobChunk(hash=sha(scene_bytes), offset=0, data=scene_bytes)
requests = {
    "missing-blobs": request(MISSING, pb.MissingBlobsRequest(hashes=[good_hash, "zz"]).SerializeToString()),
    "missing-blobs-garbage": request(MISSING, b"\x0a\xff\xff\xff\xff\x0f"),
    "submit-valid": request(SUBMIT, stream(pb.SubmitJobRequest(header=header),
                                           pb.SubmitJobRequest(chunk=chunk))),
    "submit-truncated-upload": request(SUBMIT, stream(
        pb.SubmitJobRequest(header=header),
        pb.SubmitJobRequest(chunk=pb.BlobChunk(hash=chunk.hash, offset=0, data=scene_bytes[:100])))),
    "submit-wrong-checksum": request(SUBMIT, stream(
        pb.SubmitJobRequest(header=header),
        pb.SubmitJobRequest(chunk=pb.BlobChunk(hash=chunk.hash, offset=0, data=b"x" * len(scene_bytes))))),
    "submit-offset-gap": request(SUBMIT, stream(
        pb.SubmitJobRequest(header=header),
        pb.SubmitJobRequest(chunk=pb.BlobChunk(hash=chunk.hash, offset=7, data=scene_bytes)))),
    "submit-hostile-path": request(SUBMIT, stream(pb.SubmitJobRequest(header=pb.JobHeader(
        settings=settings, scene_path="../../etc/passwd",
        manifest=manifest(("../../etc/passwd", 5, good_hash)))))),
    "submit-nan-settings": request(SUBMIT, stream(pb.SubmitJobRequest(header=pb.JobHeader(
        settings=pb.RenderSettings(algorithm=pb.MLT, width=-1, height=1 << 30,
                                   time_budget_seconds=float("nan"), large_step_probability=float("inf")),
        scene_path="scene.xml", manifest=header.manifest)))),
    "submit-chunk-first": request(SUBMIT, stream(pb.SubmitJobRequest(chunk=chunk))),
    "progress-unknown": request(PROGRESS, pb.GetProgressRequest(job_id="job-000000000000").SerializeToString()),
    "progress-real": request(PROGRESS, pb.GetProgressRequest(job_id="JOB0", error_series_from=4000000000).SerializeToString()),
    "progress-long-id": request(PROGRESS, pb.GetProgressRequest(job_id="j" * 5000).SerializeToString()),
    "fetch-not-done": request(FETCH, pb.FetchImageRequest(job_id="JOB0").SerializeToString()),
    "fetch-unknown": request(FETCH, pb.FetchImageRequest(job_id="../../etc/passwd", wait=True).SerializeToString()),
    "cancel-unknown": request(CANCEL, pb.CancelJobRequest(job_id="job-ffffffffffff").SerializeToString()),
    "list": request(LIST, b""),
    "watch-real": request(WATCH, pb.WatchJobRequest(job_id="JOB0", interval_ms=1).SerializeToString()),
    "watch-unknown": request(WATCH, pb.WatchJobRequest(job_id="nope", interval_ms=4000000000).SerializeToString()),
    "register-wrong-protocol": request(REGISTER, pb.RegisterWorkerRequest(protocol_version=1, threads=1).SerializeToString()),
    "register-absurd": request(REGISTER, pb.RegisterWorkerRequest(
        protocol_version=PROTOCOL_VERSION, threads=-7, capabilities=["pt", "x" * 1000], host="h" * 100000).SerializeToString()),
    "lease-unknown-worker": request(LEASE, pb.LeaseChainsRequest(worker_id="worker-x", max_chains=4).SerializeToString()),
    "lease-real": request(LEASE, pb.LeaseChainsRequest(worker_id="WKR0", max_chains=-5, wait_ms=-1).SerializeToString()),
    "lease-huge": request(LEASE, pb.LeaseChainsRequest(worker_id="WKR0", max_chains=2**31 - 1, wait_ms=2**31 - 1).SerializeToString()),
    "lease-held-allocations": request(LEASE, pb.LeaseChainsRequest(worker_id="WKR0", max_chains=4, pixel_allocations_held=["0" * 64] * 17 + ["x" * 100000]).SerializeToString()),
    "lease-held-not-hashes": request(LEASE, pb.LeaseChainsRequest(worker_id="WKR0", max_chains=4, pixel_allocations_held=["0" * 64, "x" * 100000]).SerializeToString()),
    "renew-foreign": request(RENEW, pb.RenewLeasesRequest(worker_id="WKR0", leases=[
        pb.LeaseRef(job_id="JOB0", chain_index=4000000000, epoch=2**64 - 1)] * 3).SerializeToString()),
    "bundle-unknown": request(BUNDLE, pb.FetchSceneBundleRequest(bundle_hash=good_hash).SerializeToString()),
    "bundle-not-a-hash": request(BUNDLE, pb.FetchSceneBundleRequest(bundle_hash="../../etc").SerializeToString()),
}


def flush(splats, width=8, height=8, checksum=None, **fields):
    h = pb.FlushHeader(worker_id="WKR0", job_id="JOB0", width=width, height=height,
                       splat_bytes=len(splats),
                       checksum=checksum if checksum is not None else sha(splats),
                       entries=[pb.FlushEntry(chain_index=0, flush_index=0, epoch=1, mutations=64)],
                       **fields)
    return request(UPLOAD, stream(pb.UploadFlushRequest(header=h), pb.UploadFlushRequest(splats=splats)))


dense = struct.pack("<192f", *([0.5] * 192))
requests.update({
    "flush-dense": flush(dense),
    "flush-wrong-size": flush(dense, width=9),
    "flush-nan": flush(struct.pack("<192f", *([float("nan")] * 192))),
    "flush-negative": flush(struct.pack("<192f", *([-1.0] * 192))),
    "flush-infinite": flush(struct.pack("<192f", *([float("inf")] * 192))),
    "flush-wrong-checksum": flush(dense, checksum=good_hash),
    "flush-truncated": flush(dense[:100], checksum=sha(dense)),
    "flush-sparse-unsorted": flush(struct.pack("<I3fI3f", 5, 1, 1, 1, 2, 1, 1, 1), sparse=True,
                                   raw_splat_bytes=32),
    "flush-sparse-out-of-range": flush(struct.pack("<I3f", 4000000000, 1, 1, 1), sparse=True,
                                       raw_splat_bytes=16),
    "flush-compressed-garbage": flush(b"\x28\xb5\x2f\xfd" + b"\xff" * 40, compressed=True,
                                      raw_splat_bytes=768),
    "flush-unknown-job": request(UPLOAD, stream(pb.UploadFlushRequest(header=pb.FlushHeader(
        worker_id="WKR0", job_id="job-000000000000", width=8, height=8, splat_bytes=0)))),
    "flush-batch-absurd": request(UPLOAD, stream(pb.UploadFlushRequest(header=pb.FlushHeader(
        worker_id="WKR0", job_id="JOB0", width=8, height=8, splat_bytes=len(dense),
        checksum=sha(dense), entries=[pb.FlushEntry(chain_index=i, epoch=1) for i in range(5000)])),
        pb.UploadFlushRequest(splats=dense))),
})
for name, data in requests.items():
    write("requests", name, data)

print("wrote", sum(len(os.listdir(os.path.join(CORPUS, t))) for t in os.listdir(CORPUS)),
      "inputs under", os.path.relpath(CORPUS, ROOT))
