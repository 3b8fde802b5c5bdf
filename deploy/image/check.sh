#!/bin/bash
# Builds the farm's image from deploy/Dockerfile and checks it: the three programs start as the
# image's unprivileged user, `farm render` renders the Cornell box inside it, and a
# coordinator, a worker and `farm submit`/`fetch` render a job on the container's loopback.
# The images land in OUT (default ./out/image-check).
#
#   deploy/image/check.sh [SHARED] [OUT]      (from the repository's root; SHARED: ../shared)
#
# Uses buildah (`apt-get install buildah`), which needs no daemon: with Docker, build with
# `docker build -f deploy/Dockerfile -t farm .` and run the same commands with `docker run`.
# Where no registry is reachable, give buildah a debian:12 first, e.g.
#   debootstrap --variant=minbase bookworm /tmp/rootfs http://deb.debian.org/debian
#   tar -C /tmp/rootfs -c . | buildah import - docker.io/library/debian:12  (and :12-slim)
set -euo pipefail
shared=$(realpath "${1:-../shared}")
out=$(realpath -m "${2:-out/image-check}")
[ -f "$shared/scenes/cornell-box/scene.xml" ] || { echo "no $shared/scenes/cornell-box" >&2; exit 2; }
buildah bud --isolation chroot --network host -f deploy/Dockerfile -t farm .
mkdir -p "$out" && chmod 777 "$out"
c=$(buildah from localhost/farm)
trap 'buildah rm "$c" >/dev/null' EXIT
run() { buildah run --isolation chroot -v "$shared":/shared:ro -v "$out":/out "$c" -- "$@"; }
buildah inspect --format 'user {{.OCIv1.Config.User}}, ports {{.OCIv1.Config.ExposedPorts}}' "$c"
for p in farm-coordinator farm-worker farm; do run "$p" --help | head -1; done
run id
run farm render /shared/scenes/cornell-box/scene.xml --algorithm pssmlt --time 5 \
  --width 128 --height 128 -o /out/render.exr
run bash -c 'set -e; cd /tmp
farm-coordinator --listen 127.0.0.1:50151 >coordinator.log 2>&1 &
farm-worker --coordinator 127.0.0.1:50151 --threads 2 >worker.log 2>&1 &
sleep 1
job=$(farm submit --coordinator 127.0.0.1:50151 /shared/scenes/cornell-box/scene.xml \
      --width 64 --height 64 --mpp 16 | tail -1)
farm fetch --coordinator 127.0.0.1:50151 "$job" -o /out/farm.exr
farm status --coordinator 127.0.0.1:50151 "$job" | head -3
kill %1 %2'
for f in render.exr farm.exr; do [ -s "$out/$f" ] || { echo "no $out/$f" >&2; exit 1; }; done
echo "image check passed: $out/render.exr, $out/farm.exr"
