#!/usr/bin/python3
"""Big scenes for load time and memory (issue 45, part 5), written to OUT_DIR:

  mesh.ply, mesh.obj     one rippled sheet of --triangles triangles (binary PLY; OBJ text)
  scene-ply.xml          Mitsuba: a floor, a light above, the sheet from mesh.ply
  scene-obj.xml          the same from mesh.obj
  instances.pbrt         pbrt-v4: a --instance-triangles sheet defined once (ObjectBegin) and
                         placed --instances times (ObjectInstance) over a floor

  /usr/bin/python3 tools/big_scene.py OUT_DIR [--triangles 10000000]
  /usr/bin/time -v build/bin/farm render OUT_DIR/scene-ply.xml --algorithm pt --spp 1 \\
      --width 64 --height 64 -o /tmp/big.exr    # the report's load time; time's maximum RSS

The sheet is a grid of n x n cells (two triangles each) over [-1, 1]^2, rippled in height so
that its triangles are not coplanar; n is the smallest that reaches --triangles.
"""
import argparse
import math
import os

import numpy as np


def sheet(triangles):
    """Vertices (float32, k x 3) and faces (int32, m x 3) of a rippled n x n grid."""
    n = max(1, math.ceil(math.sqrt(triangles / 2)))
    u = np.linspace(-1.0, 1.0, n + 1, dtype=np.float64)
    x, z = np.meshgrid(u, u)
    y = 0.05 * np.sin(9 * x) * np.cos(7 * z)
    vertices = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(np.float32)
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    a = (j * (n + 1) + i).ravel()
    b, c, d = a + 1, a + n + 1, a + n + 2
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)]).astype(np.int32)
    return vertices, faces


def write_ply(path, vertices, faces):
    with open(path, 'wb') as f:
        f.write((f'ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n'
                 'property float x\nproperty float y\nproperty float z\n'
                 f'element face {len(faces)}\nproperty list uchar int vertex_indices\n'
                 'end_header\n').encode())
        f.write(vertices.astype('<f4').tobytes())
        records = np.zeros(len(faces), dtype=[('n', 'u1'), ('v', '<i4', 3)])
        records['n'] = 3
        records['v'] = faces
        f.write(records.tobytes())


def write_obj(path, vertices, faces, chunk=1 << 20):
    with open(path, 'w') as f:
        for s in range(0, len(vertices), chunk):
            v = vertices[s:s + chunk]
            f.write(''.join(f'v {a:.6f} {b:.6f} {c:.6f}\n' for a, b, c in v.tolist()))
        for s in range(0, len(faces), chunk):
            t = faces[s:s + chunk] + 1
            f.write(''.join(f'f {a} {b} {c}\n' for a, b, c in t.tolist()))


MITSUBA = '''<?xml version="1.0" encoding="utf-8"?>
<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="5"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 2, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="3"/><rotate x="1" angle="-90"/><translate y="-0.2"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="2"/></transform>
    <emitter type="area"><rgb name="radiance" value="10, 10, 10"/></emitter>
  </shape>
  <shape type="{kind}">
    <string name="filename" value="{file}"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.4, 0.3"/></bsdf>
  </shape>
</scene>
'''


def write_instances(path, triangles, instances):
    vertices, faces = sheet(triangles)
    side = math.ceil(math.sqrt(instances))
    with open(path, 'w') as f:
        f.write('LookAt 0 12 14  0 0 0  0 1 0\nCamera "perspective" "float fov" [ 45 ]\n'
                'Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 64 ]\n'
                'WorldBegin\n'
                'AttributeBegin\n  Translate 0 6 0\n  Rotate 90 1 0 0\n'
                '  AreaLightSource "diffuse" "rgb L" [ 20 20 20 ]\n'
                '  Shape "bilinearmesh" "point3 P" [ -1 -1 0  1 -1 0  -1 1 0  1 1 0 ]\n'
                'AttributeEnd\n'
                'Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]\n'
                'Shape "bilinearmesh" "point3 P" [ -20 -0.2 -20  20 -0.2 -20  -20 -0.2 20  20 -0.2 20 ]\n'
                'ObjectBegin "sheet"\n  Shape "trianglemesh"\n    "point3 P" [ ')
        f.write(' '.join(f'{v:.5f}' for v in vertices.ravel().tolist()))
        f.write(' ]\n    "integer indices" [ ')
        f.write(' '.join(str(i) for i in faces.ravel().tolist()))
        f.write(' ]\nObjectEnd\n')
        for k in range(instances):
            x, z = (k % side - side / 2) * 2.2, (k // side - side / 2) * 2.2
            f.write(f'AttributeBegin\n  Translate {x:.2f} 0 {z:.2f}\n  ObjectInstance "sheet"\n'
                    'AttributeEnd\n')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('--triangles', type=int, default=10_000_000)
    ap.add_argument('--instance-triangles', type=int, default=20_000)
    ap.add_argument('--instances', type=int, default=500)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    vertices, faces = sheet(a.triangles)
    write_ply(os.path.join(a.out, 'mesh.ply'), vertices, faces)
    write_obj(os.path.join(a.out, 'mesh.obj'), vertices, faces)
    for kind, file in [('ply', 'mesh.ply'), ('obj', 'mesh.obj')]:
        with open(os.path.join(a.out, f'scene-{kind}.xml'), 'w') as f:
            f.write(MITSUBA.format(kind=kind, file=file))
    write_instances(os.path.join(a.out, 'instances.pbrt'), a.instance_triangles, a.instances)
    print(f'{a.out}: {len(faces)} triangles, {len(vertices)} vertices; '
          f'{a.instances} instances of {2 * math.ceil(math.sqrt(a.instance_triangles / 2)) ** 2}')


if __name__ == '__main__':
    main()
