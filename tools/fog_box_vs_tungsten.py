#!/usr/bin/python3
"""The fog box of issue 43, part 2, in the farm and in Tungsten, region by region.

A Cornell-like room (2 x 2 x 2, open towards the camera) whose inside is a box of fog (null
boundaries 2 cm inside the walls; sigma_s 1, no absorption, isotropic), a glass ball on the
floor and a tiny light under the ceiling, inside the fog. The scene is written from one
description in both formats (Mitsuba XML for the farm, Tungsten's JSON: the shared converter
knows no media), each renderer renders it with its bidirectional path tracer at two seeds, and
the table gives each region's mean (near the light, the walls, floor and ceiling, the ball,
the caustic under it) for each image, with the spread between seeds.

Tungsten starts a light's paths in the light primitive's own ext_medium, and in vacuum when it
has none, whatever surrounds it; the farm finds the medium around the light
(Scene::mediumAt). --tungsten-light-medium gives Tungsten's light ext_medium "fog", as the
scene means; without it, Tungsten's light emits into vacuum inside the fog.

    tools/fog_box_vs_tungsten.py OUT --tungsten TUNGSTEN [--farm build/bin/farm] [--size 128]
                                 [--time 60] [--tungsten-light-medium]

The closed forms of common/render/media_closed_form_test.cpp check the farm's media with no
renderer beside it (single scattering, a slab, a ball of albedo one that lets all of its
light's power out).
"""
import argparse
import json
import math
import os
import subprocess

import numpy as np
import OpenImageIO as oiio

SIGMA_S = 1.0
G = 0.0
FOG_HALF = 0.98
LIGHT_HALF = 0.03  # the light's half side
LIGHT_Y = 1.9
LIGHT_RADIANCE = [400.0, 380.0, 340.0]
BALL = ([0.3, 0.35, 0.1], 0.35)  # centre, radius
IOR = 1.5
WHITE, RED, GREEN = [0.75] * 3, [0.6, 0.08, 0.08], [0.1, 0.55, 0.1]
CAMERA = ([0.0, 1.0, -3.4], [0.0, 1.0, 0.0], 40.0)  # position, target, fov


def translate(x, y, z):
    return np.array([[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]], float)


def scale(x, y, z):
    return np.diag([x, y, z, 1.0])


def rotate(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


# Mitsuba's rectangle is [-1, 1]^2 in xy with its normal +z; Tungsten's quad is the unit square
# in xz with its normal +y: this takes Tungsten's to Mitsuba's. Mitsuba's cube is [-1, 1]^3,
# Tungsten's [-0.5, 0.5]^3.
QUAD_TO_RECTANGLE = np.array([[2, 0, 0, 0], [0, 0, -2, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)
UNIT_TO_CUBE = scale(2, 2, 2)


def rectangles():
    """(name, matrix, reflectance) of the room's faces, normals inwards."""
    return [
        ("floor", translate(0, 0, 0) @ rotate("x", -90), WHITE),
        ("ceiling", translate(0, 2, 0) @ rotate("x", 90), WHITE),
        ("back", translate(0, 1, 1) @ rotate("y", 180), WHITE),
        ("left", translate(-1, 1, 0) @ rotate("y", 90), RED),
        ("right", translate(1, 1, 0) @ rotate("y", -90), GREEN),
    ]


def light_matrix():
    return translate(0, LIGHT_Y, 0) @ rotate("x", 90) @ scale(LIGHT_HALF, LIGHT_HALF, 1)


def fog_matrix():
    return translate(0, 1, 0) @ scale(FOG_HALF, FOG_HALF, FOG_HALF)


def matrix_xml(m):
    return '<transform name="toWorld"><matrix value="%s"/></transform>' % " ".join(
        "%.9g" % v for v in m.flatten())


def rgb(v):
    return ", ".join("%g" % x for x in v)


def mitsuba_scene():
    pos, target, fov = CAMERA
    lines = ['<?xml version="1.0"?>', '<scene version="0.5.0">',
             '  <integrator type="path"><integer name="maxDepth" value="64"/></integrator>',
             '  <sensor type="perspective"><float name="fov" value="%g"/>' % fov,
             '    <transform name="toWorld"><lookat origin="%s" target="%s" up="0, 1, 0"/>'
             '</transform>' % (rgb(pos), rgb(target)),
             '    <film type="hdrfilm"><integer name="width" value="128"/>'
             '<integer name="height" value="128"/></film>', '  </sensor>',
             '  <medium type="homogeneous" id="fog"><rgb name="sigmaA" value="0, 0, 0"/>'
             '<rgb name="sigmaS" value="%s"/><phase type="hg"><float name="g" value="%g"/>'
             '</phase></medium>' % (rgb([SIGMA_S] * 3), G)]
    for _, m, albedo in rectangles():
        lines.append('  <shape type="rectangle">%s<bsdf type="twosided"><bsdf type="diffuse">'
                     '<rgb name="reflectance" value="%s"/></bsdf></bsdf></shape>'
                     % (matrix_xml(m), rgb(albedo)))
    lines.append('  <shape type="rectangle">%s<bsdf type="diffuse"><rgb name="reflectance" '
                 'value="0, 0, 0"/></bsdf><emitter type="area"><rgb name="radiance" value="%s"/>'
                 '</emitter></shape>' % (matrix_xml(light_matrix()), rgb(LIGHT_RADIANCE)))
    lines.append('  <shape type="cube">%s<ref name="interior" id="fog"/></shape>'
                 % matrix_xml(fog_matrix()))
    lines.append('  <shape type="sphere"><point name="center" x="%g" y="%g" z="%g"/>'
                 '<float name="radius" value="%g"/><bsdf type="dielectric"><float name="intIOR" '
                 'value="%g"/><float name="extIOR" value="1"/></bsdf><ref name="exterior" '
                 'id="fog"/></shape>' % (*BALL[0], BALL[1], IOR))
    lines.append("</scene>")
    return "\n".join(lines) + "\n"


def tungsten_scene(size, spp, light_medium, out_pfm):
    pos, target, fov = CAMERA
    bsdfs = [{"name": "fog-boundary", "type": "forward"},
             {"name": "black", "type": "lambert", "albedo": 0.0},
             {"name": "glass", "type": "dielectric", "ior": IOR, "enable_refraction": True}]
    prims = []
    for name, m, albedo in rectangles():
        bsdfs.append({"name": name, "type": "lambert", "albedo": albedo})
        prims.append({"type": "quad", "transform": list((m @ QUAD_TO_RECTANGLE).flatten()),
                      "bsdf": name})
    light = {"type": "quad", "transform": list((light_matrix() @ QUAD_TO_RECTANGLE).flatten()),
             "bsdf": "black", "emission": LIGHT_RADIANCE}
    if light_medium:
        light["ext_medium"] = "fog"
    prims.append(light)
    prims.append({"type": "cube", "transform": list((fog_matrix() @ UNIT_TO_CUBE).flatten()),
                  "bsdf": "fog-boundary", "int_medium": "fog"})
    prims.append({"type": "sphere", "transform": {"position": BALL[0], "scale": BALL[1]},
                  "bsdf": "glass", "ext_medium": "fog"})
    return {
        "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0.0, "sigma_s": SIGMA_S,
                   "density": 1.0, "phase_function": {"type": "henyey_greenstein", "g": G},
                   "max_bounces": 1024}],
        "bsdfs": bsdfs, "primitives": prims,
        "camera": {"type": "pinhole", "fov": fov, "resolution": [size, size],
                   "reconstruction_filter": "box", "tonemap": "gamma",
                   "transform": {"position": pos, "look_at": target, "up": [0, 1, 0]}},
        "integrator": {"type": "bidirectional_path_tracer", "min_bounces": 0, "max_bounces": 64,
                       "enable_two_sided_shading": True},
        "renderer": {"output_file": out_pfm[:-4] + ".png", "hdr_output_file": out_pfm,
                     "overwrite_output_files": True, "adaptive_sampling": False,
                     "enable_resume_render": False, "stratified_sampler": False,
                     "scene_bvh": True, "spp": spp, "spp_step": 16, "checkpoint_interval": "0",
                     "timeout": "0"},
    }


def load(path):
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT), dtype=np.float64)[..., :3]


def regions(size):
    """Each pixel's region, by its central camera ray against the scene's geometry (the fog
    does not bend rays, the glass does not matter to which surface a ray meets first)."""
    pos, target, fov = (np.array(CAMERA[0]), np.array(CAMERA[1]), CAMERA[2])
    forward = (target - pos) / np.linalg.norm(target - pos)
    right = np.cross([0, 1, 0], forward)  # image +x (Tungsten and Mitsuba flip it alike)
    up = np.cross(forward, right)
    t = math.tan(math.radians(fov) / 2)
    light_centre = np.array([0.0, LIGHT_Y, 0.0])
    out = np.empty((size, size), dtype=object)
    for j in range(size):
        for i in range(size):
            sx = (1 - 2 * (i + 0.5) / size) * t  # Mitsuba's +x is the image's left
            sy = (1 - 2 * (j + 0.5) / size) * t
            d = forward + sx * right + sy * up
            d /= np.linalg.norm(d)
            # Near the light: within 12 cm of the ray.
            v = light_centre - pos
            if np.linalg.norm(v - d * np.dot(v, d)) < 0.12:
                out[j, i] = "near the light"
                continue
            c, r = np.array(BALL[0]), BALL[1]
            oc = pos - c
            b = np.dot(oc, d)
            disc = b * b - (np.dot(oc, oc) - r * r)
            if disc > 0 and -b - math.sqrt(disc) > 0:
                out[j, i] = "ball"
                continue
            hits = []
            for name, axis, value in (("floor", 1, 0.0), ("ceiling", 1, 2.0), ("back wall", 2, 1.0),
                                      ("side walls", 0, -1.0), ("side walls", 0, 1.0)):
                if abs(d[axis]) < 1e-9:
                    continue
                s = (value - pos[axis]) / d[axis]
                p = pos + s * d
                if s > 0 and all(-1 - 1e-6 <= p[k] <= 1 + 1e-6 for k in (0, 2)) and \
                        -1e-6 <= p[1] <= 2 + 1e-6:
                    hits.append((s, name, p))
            if not hits:
                out[j, i] = "outside"
                continue
            s, name, p = min(hits, key=lambda h: h[0])
            if name == "floor" and math.hypot(p[0] - BALL[0][0], p[2] - BALL[0][2]) < 1.6 * r:
                name = "floor under the ball (caustic)"
            out[j, i] = name
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--tungsten", required=True)
    ap.add_argument("--farm", default="build/bin/farm")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--time", type=float, default=60, help="the farm's seconds a render")
    ap.add_argument("--tungsten-spp", type=int, default=256)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--tungsten-light-medium", action="store_true")
    ap.add_argument("--table-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    xml = os.path.join(a.out, "scene.xml")
    with open(xml, "w") as f:
        f.write(mitsuba_scene())
    kind = "tungsten-light-in-fog" if a.tungsten_light_medium else "tungsten"
    images = {}
    for seed in a.seeds:
        exr = os.path.join(a.out, "farm-%d.exr" % seed)
        pfm = os.path.abspath(os.path.join(a.out, "%s-%d.pfm" % (kind, seed)))
        if not a.table_only:
            subprocess.run([a.farm, "render", xml, "--algorithm", "bdpt", "--time", str(a.time),
                            "--seed", str(seed), "--width", str(a.size), "--height", str(a.size),
                            "--shading-normals", "lax", "-o", exr], check=True,
                           stdout=subprocess.DEVNULL)
            js = os.path.join(a.out, "%s-%d.json" % (kind, seed))
            with open(js, "w") as f:
                json.dump(tungsten_scene(a.size, a.tungsten_spp, a.tungsten_light_medium, pfm), f,
                          indent=1)
            subprocess.run([a.tungsten, "-t", "2", "-s", str(seed), js], check=True,
                           stdout=subprocess.DEVNULL)
        images.setdefault("farm", []).append(load(exr))
        images.setdefault(kind, []).append(load(pfm))
    region = regions(a.size)
    names = sorted(set(region.flatten()) - {"outside"})
    print("| region | pixels | " + " | ".join(images) + " | %s / farm |" % kind)
    print("|---|---|" + "---|" * (len(images) + 1))
    for name in names:
        mask = region == name
        cells, means = [], []
        for k, imgs in images.items():
            per_seed = [float(img[mask].mean()) for img in imgs]
            m = sum(per_seed) / len(per_seed)
            means.append(m)
            cells.append("%.4g (%s)" % (m, ", ".join("%.4g" % x for x in per_seed)))
        print("| %s | %d | %s | %.3f |" % (name, int(mask.sum()), " | ".join(cells),
                                           means[1] / means[0]))
    whole = [sum(float(img.mean()) for img in imgs) / len(imgs) for imgs in images.values()]
    print("| whole image | %d | %s | %.3f |" % (a.size * a.size,
                                                " | ".join("%.4g" % w for w in whole),
                                                whole[1] / whole[0]))


if __name__ == "__main__":
    main()
