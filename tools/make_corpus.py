#!/usr/bin/python3
"""A corpus of scenes no rule of the farm was fitted on (issue 42): eight families of Mitsuba 0.6
scenes with randomized parameters, three scenes each, written to OUT_DIR/<name>/scene.xml with any
texture or environment map beside it, and OUT_DIR/corpus.json listing every scene's family, its
parameters and its half: `tune` (for fitting rules and settings) or `measure` (for reporting what
they give). The halves are fixed here, by family and index, before anything is tuned on them; each
family has scenes in both.

    tools/make_corpus.py OUT_DIR [--seed N]

Same seed, same corpus (the default seed is the one the README's tables use).

Families: a room lit by a large, a small or a tiny ceiling light; a light boxed in above a plate
and reaching the room through a slot; a light inside a glass ball (seen and lit through glass);
glass, metal and glossy objects on the floor; fog, thin or thick, with a glass ball in it; an
open floor under an environment map with a sun; a room with textured walls and floor.
"""
import argparse
import json
import math
import os
import random

import numpy as np
import OpenImageIO as oiio

FAMILIES = ["large-light", "small-light", "tiny-light", "boxed-light", "light-in-glass",
            "specular-objects", "fog", "environment", "textures"]
PER_FAMILY = 3


def rgb(c):
    return "%.4g, %.4g, %.4g" % tuple(c)


def rectangle(center, normal_rotation, half, bsdf, emitter=""):
    """A rectangle (Mitsuba's spans [-1, 1]^2 in z = 0, facing +z) scaled by half = (hx, hy),
    turned by normal_rotation (a list of (axis, degrees)) and moved to center."""
    rot = "".join('<rotate %s="1" angle="%g"/>' % (a, d) for a, d in normal_rotation)
    return ('  <shape type="rectangle"><transform name="toWorld"><scale x="%g" y="%g"/>%s'
            '<translate x="%g" y="%g" z="%g"/></transform>%s%s</shape>\n'
            % (half[0], half[1], rot, center[0], center[1], center[2], bsdf, emitter))


# Orientations of a rectangle's normal.
UP, DOWN = [("x", -90)], [("x", 90)]
TOWARD_MINUS_Z, TOWARD_PLUS_X, TOWARD_MINUS_X = [("y", 180)], [("y", 90)], [("y", -90)]


def diffuse(c):
    return '<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="%s"/></bsdf></bsdf>' % rgb(c)


def light_bsdf():
    return '<bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>'


def area(radiance):
    return '<emitter type="area"><rgb name="radiance" value="%s"/></emitter>' % rgb(radiance)


def header(max_depth, width=128, height=128, origin=(0, 1, -3.4), target=(0, 1, 0), fov=40):
    return ('<?xml version="1.0"?>\n<scene version="0.5.0">\n'
            '  <integrator type="path"><integer name="maxDepth" value="%d"/></integrator>\n'
            '  <sensor type="perspective"><float name="fov" value="%g"/>\n'
            '    <transform name="toWorld"><lookat origin="%g, %g, %g" target="%g, %g, %g" up="0, 1, 0"/></transform>\n'
            '    <film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/></film>\n'
            '  </sensor>\n' % (max_depth, fov, *origin, *target, width, height))


def room(r, walls=None, floor_bsdf=None, back_bsdf=None):
    """A room x in [-1, 1], y in [0, 2], z in [-1, 1], open towards the camera (at z = -3.4):
    floor, ceiling, back wall and two side walls of random colours."""
    white = [r.uniform(0.55, 0.8)] * 3
    left = walls[0] if walls else [r.uniform(0.4, 0.7), r.uniform(0.05, 0.3), r.uniform(0.05, 0.3)]
    right = walls[1] if walls else [r.uniform(0.05, 0.3), r.uniform(0.3, 0.6), r.uniform(0.05, 0.4)]
    s = rectangle((0, 0, 0), UP, (1, 1), floor_bsdf or diffuse(white))
    s += rectangle((0, 2, 0), DOWN, (1, 1), diffuse(white))
    s += rectangle((0, 1, 1), TOWARD_MINUS_Z, (1, 1), back_bsdf or diffuse(white))
    s += rectangle((-1, 1, 0), TOWARD_PLUS_X, (1, 1), diffuse(left))
    s += rectangle((1, 1, 0), TOWARD_MINUS_X, (1, 1), diffuse(right))
    return s, {"white": white, "left": left, "right": right}


def ceiling_light(r, half, power):
    """A light facing down just below the ceiling; its radiance gives it about `power`."""
    tint = [1.0, r.uniform(0.75, 1.0), r.uniform(0.45, 0.9)]
    radiance = [power * t / (4 * half * half * math.pi) for t in tint]
    return rectangle((r.uniform(-0.2, 0.2), 1.99, r.uniform(-0.2, 0.2)), DOWN, (half, half),
                     light_bsdf(), area(radiance)), radiance


def box(center, half, bsdf, angle=0):
    return ('  <shape type="cube"><transform name="toWorld"><scale x="%g" y="%g" z="%g"/>'
            '<rotate y="1" angle="%g"/><translate x="%g" y="%g" z="%g"/></transform>%s</shape>\n'
            % (*half, angle, *center, bsdf))


def sphere(center, radius, bsdf, inside=""):
    return ('  <shape type="sphere"><point name="center" x="%g" y="%g" z="%g"/>'
            '<float name="radius" value="%g"/>%s%s</shape>\n' % (*center, radius, bsdf, inside))


def glass(ior):
    return ('<bsdf type="dielectric"><float name="intIOR" value="%g"/>'
            '<float name="extIOR" value="1"/></bsdf>' % ior)


def two_boxes(r):
    white = diffuse([r.uniform(0.5, 0.8)] * 3)
    return (box((r.uniform(-0.6, -0.2), 0.6, r.uniform(0.0, 0.5)), (0.28, 0.6, 0.28), white,
                r.uniform(-30, 30)) +
            box((r.uniform(0.2, 0.6), 0.3, r.uniform(-0.5, 0.0)), (0.28, 0.3, 0.28), white,
                r.uniform(-30, 30)))


def lit_room(r, half, power):
    walls, colours = room(r)
    light, radiance = ceiling_light(r, half, power)
    return walls + light + two_boxes(r), {"light_half_size": half, "radiance": radiance, **colours}


def make_room_light(smallest, largest):
    """The three room families: a ceiling light of half-size in [smallest, largest]."""
    def make(r, _dir):
        body, p = lit_room(r, r.uniform(smallest, largest), r.uniform(6, 12))
        return header(r.choice([8, 16, 65])) + body, p
    return make


def make_boxed_light(r, _dir):
    """The issue's boxed light: a ceiling light above a plate that covers the ceiling but for a
    slot along one wall, so that light reaches the room through the slot, mostly after bouncing
    between the plate and the ceiling."""
    walls, colours = room(r)
    slot = r.uniform(0.04, 0.2)
    plate_y = r.uniform(1.75, 1.9)
    half = r.uniform(0.3, 0.6)
    tint = [1.0, r.uniform(0.8, 1.0), r.uniform(0.5, 0.9)]
    radiance = [r.uniform(20, 60) * t for t in tint]
    s = walls
    s += rectangle((0, 1.99, 0), DOWN, (half, half), light_bsdf(), area(radiance))
    # The plate: x in [-1, 1 - slot], two-sided, white.
    width = (2 - slot) / 2
    s += rectangle((-1 + width, plate_y, 0), UP, (width, 1), diffuse([0.75, 0.75, 0.75]))
    s += two_boxes(r)
    return header(r.choice([16, 65])) + s, {"slot": slot, "plate_y": plate_y,
                                            "light_half_size": half, "radiance": radiance, **colours}


def make_light_in_glass(r, _dir):
    """A small light inside a glass ball hanging below the ceiling: the camera sees it through
    glass and the room is lit through glass (no direct connection reaches it)."""
    walls, colours = room(r)
    ior = r.uniform(1.3, 1.8)
    radius = r.uniform(0.12, 0.3)
    centre = (r.uniform(-0.3, 0.3), 1.95 - radius - r.uniform(0.05, 0.3), r.uniform(-0.2, 0.3))
    half = radius * r.uniform(0.15, 0.35)
    radiance = [r.uniform(30, 80)] * 3
    s = walls + sphere(centre, radius, glass(ior))
    s += rectangle(centre, DOWN, (half, half), light_bsdf(), area(radiance))
    s += two_boxes(r)
    return header(r.choice([16, 65])) + s, {"ior": ior, "radius": radius,
                                            "light_half_size": half, **colours}


def make_specular_objects(r, _dir):
    """Glass, metal and glossy objects on the floor under a light of random size."""
    body, p = lit_room(r, r.uniform(0.05, 0.4), r.uniform(6, 12))
    ior = r.uniform(1.3, 2.0)
    alpha = r.uniform(0.02, 0.3)
    metal = [r.uniform(0.2, 1.0) for _ in range(3)]
    s = body
    s += sphere((r.uniform(-0.5, 0.5), 0.25, r.uniform(-0.7, -0.4)), 0.25, glass(ior))
    s += sphere((r.uniform(-0.6, -0.3), 0.2, r.uniform(-0.3, 0.0)), 0.2,
                '<bsdf type="conductor"><string name="material" value="none"/>'
                '<rgb name="specularReflectance" value="%s"/></bsdf>' % rgb(metal))
    s += sphere((r.uniform(0.3, 0.6), 0.2, r.uniform(-0.3, 0.0)), 0.2,
                '<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
                '<float name="alpha" value="%g"/></bsdf>' % alpha)
    s += sphere((0.0, 0.15, r.uniform(-0.1, 0.2)), 0.15,
                '<bsdf type="roughplastic"><float name="alpha" value="%g"/>'
                '<rgb name="diffuseReflectance" value="%s"/></bsdf>'
                % (r.uniform(0.05, 0.3), rgb([r.uniform(0.1, 0.8) for _ in range(3)])))
    return header(r.choice([16, 65])) + s, {**p, "ior": ior, "alpha": alpha, "metal": metal}


def make_fog(r, _dir):
    """Fog filling the room, thin or thick, around a glass ball, under a small light."""
    thick = r.random() < 0.5
    sigma_s = r.uniform(0.5, 1.5) if thick else r.uniform(0.03, 0.2)
    albedo_gap = r.uniform(0.0, 0.1)
    g = r.uniform(-0.2, 0.7)
    body, p = lit_room(r, r.uniform(0.05, 0.25), r.uniform(6, 12))
    medium = ('  <medium type="homogeneous" id="fog"><rgb name="sigmaA" value="%s"/>'
              '<rgb name="sigmaS" value="%s"/><phase type="hg"><float name="g" value="%g"/>'
              '</phase></medium>\n' % (rgb([sigma_s * albedo_gap] * 3), rgb([sigma_s] * 3), g))
    s = medium + body
    # The fog's boundary, inside the room's walls, and a glass ball in it.
    s += box((0, 1.0, 0.0), (0.98, 0.98, 0.98), '<ref name="interior" id="fog"/>')
    ior = r.uniform(1.3, 1.8)
    s += sphere((r.uniform(-0.4, 0.4), 0.3, r.uniform(-0.6, -0.3)), 0.28, glass(ior),
                '<ref name="exterior" id="fog"/>')
    return header(r.choice([16, 32])) + s, {**p, "sigma_s": sigma_s, "thick": thick, "g": g,
                                            "ior": ior}


def write_image(path, pixels):
    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(path)
    spec = oiio.ImageSpec(w, h, c, oiio.UINT8 if path.endswith(".png") else oiio.FLOAT)
    out.open(path, spec)
    out.write_image(pixels)
    out.close()


def make_environment(r, directory):
    """An open floor with objects under a lat-long sky (a gradient, and a sun of random size and
    height written into the map)."""
    w, h = 256, 128
    sun_elevation = r.uniform(10, 60)
    sun_azimuth = r.uniform(0, 360)
    sun_radius = r.uniform(1.0, 6.0)  # degrees
    sun_power = r.uniform(3e2, 3e3) * (1.0 / sun_radius) ** 2
    sky = np.zeros((h, w, 3), np.float32)
    for j in range(h):
        elevation = 90 - 180 * (j + 0.5) / h
        t = max(elevation, 0) / 90
        sky[j, :, :] = [0.3 + 0.3 * t, 0.45 + 0.35 * t, 0.8 + 0.2 * t] if elevation > 0 else [0.1, 0.1, 0.1]
    se, sa = math.radians(sun_elevation), math.radians(sun_azimuth)
    for j in range(h):
        elevation = math.radians(90 - 180 * (j + 0.5) / h)
        for i in range(w):
            azimuth = math.radians(360 * (i + 0.5) / w)
            cos_angle = (math.sin(elevation) * math.sin(se) +
                         math.cos(elevation) * math.cos(se) * math.cos(azimuth - sa))
            if math.degrees(math.acos(max(-1.0, min(1.0, cos_angle)))) < sun_radius:
                sky[j, i, :] = [sun_power, sun_power * 0.9, sun_power * 0.75]
    write_image(os.path.join(directory, "sky.exr"), sky)
    s = header(r.choice([8, 16]), origin=(0, 1.5, -4.5), target=(0, 0.4, 0), fov=45)
    s += '  <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>\n'
    s += rectangle((0, 0, 0), UP, (4, 4), diffuse([r.uniform(0.3, 0.7)] * 3))
    s += two_boxes(r)
    s += sphere((r.uniform(-0.5, 0.5), 0.3, -0.8), 0.3, glass(r.uniform(1.3, 1.8)))
    return s, {"sun_elevation": sun_elevation, "sun_azimuth": sun_azimuth,
               "sun_radius": sun_radius, "sun_power": sun_power}


def make_textures(r, directory):
    """Checkered floor and back wall (PNG textures of random scale and colours)."""
    n = r.choice([4, 8, 16])
    a = np.array([r.uniform(0.5, 0.9) for _ in range(3)])
    b = np.array([r.uniform(0.05, 0.4) for _ in range(3)])
    size = 64
    tile = np.zeros((size, size, 3), np.float32)
    for j in range(size):
        for i in range(size):
            tile[j, i] = a if ((i * n // size) + (j * n // size)) % 2 == 0 else b
    write_image(os.path.join(directory, "checks.png"), (tile * 255 + 0.5).astype(np.uint8))
    textured = ('<bsdf type="twosided"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                '<string name="filename" value="checks.png"/></texture></bsdf></bsdf>')
    walls, colours = room(r, floor_bsdf=textured, back_bsdf=textured)
    light, radiance = ceiling_light(r, r.uniform(0.05, 0.5), r.uniform(6, 12))
    return header(r.choice([8, 16, 65])) + walls + light + two_boxes(r), {
        "checks": n, "colour_a": a.tolist(), "colour_b": b.tolist(), "radiance": radiance, **colours}


MAKERS = {
    "large-light": make_room_light(0.5, 0.9), "small-light": make_room_light(0.08, 0.2),
    "tiny-light": make_room_light(0.005, 0.02), "boxed-light": make_boxed_light,
    "light-in-glass": make_light_in_glass, "specular-objects": make_specular_objects,
    "fog": make_fog, "environment": make_environment, "textures": make_textures,
}


def half_of(family_index, index):
    """Fixed before any tuning: within a family the halves alternate, and the families alternate
    which half comes first, so each family has scenes in both and the halves are 14 and 13."""
    return "tune" if (family_index + index) % 2 == 0 else "measure"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--seed", type=int, default=42)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    entries = []
    for fi, family in enumerate(FAMILIES):
        for index in range(PER_FAMILY):
            r = random.Random("%d/%s/%d" % (a.seed, family, index))
            name = "%s-%d" % (family, index)
            directory = os.path.join(a.out, name)
            os.makedirs(directory, exist_ok=True)
            body, params = MAKERS[family](r, directory)
            with open(os.path.join(directory, "scene.xml"), "w") as f:
                f.write(body + "</scene>\n")
            entries.append({"name": name, "family": family, "half": half_of(fi, index),
                            "scene": os.path.join(name, "scene.xml"), "parameters": params})
    with open(os.path.join(a.out, "corpus.json"), "w") as f:
        json.dump({"seed": a.seed, "scenes": entries}, f, indent=1)
    print("wrote %d scenes to %s (tune: %d, measure: %d)" % (
        len(entries), a.out, sum(e["half"] == "tune" for e in entries),
        sum(e["half"] == "measure" for e in entries)))


if __name__ == "__main__":
    main()
