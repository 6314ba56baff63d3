"""Runs inside Blender (blender -b --factory-startup --python-exit-code 1 --python check_loader.py -- TOOLS_DIR WORK_DIR):
writes a small run directory (two frames of a box mesh as OBJ, of a volume
as VDB with the grids density, vel and magnetization, field lines as OBJ,
and a scene file with a sphere magnet), loads it with
tools/blender/load_lodestone.py and checks the objects' bounds, visibility
per frame, grid names and curve splines. Any failed check raises (exit 1)."""
import json
import os
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
tools_dir, work = args[0], args[1]
sys.path.insert(0, tools_dir)
import load_lodestone  # noqa: E402

run = os.path.join(work, "run")
os.makedirs(run, exist_ok=True)
for name in os.listdir(run):
    os.remove(os.path.join(run, name))


def box_obj(path, lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    faces = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]
    with open(path, "w") as f:
        for p in v:
            f.write("v %.9g %.9g %.9g\n" % p)
        for q in faces:
            f.write("f %d %d %d %d\n" % q)


LO, HI = (0.01, -0.01, 0.0), (0.03, 0.01, 0.02)
SHIFT = 0.005  # m, frame 2 moves along x
box_obj(os.path.join(run, "mesh_0001.obj"), LO, HI)
box_obj(os.path.join(run, "mesh_0002.obj"), (LO[0] + SHIFT, LO[1], LO[2]), (HI[0] + SHIFT, HI[1], HI[2]))

DX = 0.002  # m, voxel size
import pyopenvdb as vdb  # noqa: E402  (Blender's own OpenVDB module)

for frame, i0 in ((1, 0), (2, 5)):
    density = vdb.FloatGrid()
    density.name = "density"
    density.transform = vdb.createLinearTransform(voxelSize=DX)
    density.fill((i0, 0, 0), (i0 + 9, 4, 4), 0.8)
    mag = vdb.FloatGrid()
    mag.name = "magnetization"
    mag.transform = density.transform
    mag.fill((i0, 0, 0), (i0 + 9, 4, 4), 3e5)
    vel = vdb.Vec3SGrid()
    vel.name = "vel"
    vel.transform = density.transform
    vel.fill((i0, 0, 0), (i0 + 9, 4, 4), (0.1, 0.0, 0.0))
    vdb.write(os.path.join(run, "volume_%04d.vdb" % frame), grids=[density, vel, mag])

with open(os.path.join(run, "field_lines_0001.obj"), "w") as f:
    f.write("# field lines\nv 0 0 0\nv 0.01 0 0\nv 0.02 0 0.01\nv 0 0.05 0\nv 0.01 0.05 0\nv 0.01 0.06 0\n")
    f.write("l 1 2 3\nl 4 5 6 4\n")
scene_path = os.path.join(work, "scene.json")
with open(scene_path, "w") as f:
    json.dump({"time": {"fps": 30}, "magnets": [{"shape": "sphere", "center": [0, 0, 0.05], "radius": 0.01,
                                                 "magnetization": 1e6}]}, f)

result = load_lodestone.load_run(run, scene_path)
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def world_bounds(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    pts = [ev.matrix_world @ Vector(c) for c in ev.bound_box]
    return [min(p[a] for p in pts) for a in range(3)], [max(p[a] for p in pts) for a in range(3)]


def near(a, b, tol):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


scene = bpy.context.scene
check(scene.render.fps == 30, "fps from the scene file (%d)" % scene.render.fps)
check((scene.frame_start, scene.frame_end) == (1, 2), "frame range 1..2 (%d..%d)" % (scene.frame_start, scene.frame_end))

meshes = result["meshes"]
check(len(meshes) == 2, "two mesh frames (%d)" % len(meshes))
scene.frame_set(1)
lo, hi = world_bounds(meshes[0])
check(near(lo, LO, 1e-6) and near(hi, HI, 1e-6), "mesh 1 bounds %s %s" % (lo, hi))
lo, hi = world_bounds(meshes[1])
check(near(lo, (LO[0] + SHIFT, LO[1], LO[2]), 1e-6), "mesh 2 bounds %s %s" % (lo, hi))
check(not meshes[0].hide_render and meshes[1].hide_render, "frame 1 shows mesh 1 only")
scene.frame_set(2)
check(meshes[0].hide_render and not meshes[1].hide_render, "frame 2 shows mesh 2 only")

vol = result["volume"]
check(vol is not None and vol.type == "VOLUME", "a volume object")
data = vol.data
check(data.is_sequence and data.frame_start == 1 and data.frame_duration == 2, "the volume is a 2-frame sequence")
scene.frame_set(1)
data.grids.load()
names = sorted(g.name for g in data.grids)
check(names == ["density", "magnetization", "vel"], "grid names %s" % names)
# Blender's volume bounds are those of the grids' active tiles and voxels
# (not per-voxel tight): they hold the active index box 0..9 x 0..4 x 0..4
# (and frame 2's 5..14) and stay within one 8-voxel leaf of it.
lo, hi = world_bounds(vol)
check(near(lo, (0, 0, 0), 0.51 * DX) and all(h >= e for h, e in zip(hi, (10 * DX, 5 * DX, 5 * DX)))
      and all(h <= e for h, e in zip(hi, (16 * DX, 8 * DX, 8 * DX))), "volume bounds %s %s" % (lo, hi))
ev = vol.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
check(ev.grids.frame_filepath.endswith("volume_0001.vdb"), "frame 1 reads volume_0001.vdb (%s)" % ev.grids.frame_filepath)
voxel = [list(ev.grids[0].matrix_object)[a][a] for a in range(3)]
check(near(voxel, (DX, DX, DX), 1e-9), "the grid's voxel size %s m" % voxel)
scene.frame_set(2)
ev = vol.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
check(ev.grids.frame_filepath.endswith("volume_0002.vdb"), "frame 2 reads volume_0002.vdb (%s)" % ev.grids.frame_filepath)
mat = data.materials[0]
pv = [n for n in mat.node_tree.nodes if n.type == "PRINCIPLED_VOLUME"]
check(len(pv) == 1 and pv[0].inputs["Density Attribute"].default_value == "density",
      "Principled Volume reads density")

lines = result["field_lines"]
check(len(lines) == 1, "one field-line frame")
splines = lines[0].data.splines
check(len(splines) == 2, "two splines (%d)" % len(splines))
check(len(splines[0].points) == 3 and not splines[0].use_cyclic_u, "an open line of 3 points")
check(len(splines[1].points) == 3 and splines[1].use_cyclic_u, "a closed line of 3 points, cyclic")
check(near(splines[0].points[2].co[:3], (0.02, 0, 0.01), 1e-9), "line vertex positions")

mags = result["magnets"]
check(len(mags) == 1 and near(mags[0].location, (0, 0, 0.05), 1e-9), "the sphere magnet at its centre")
check(near(mags[0].dimensions, (0.02, 0.02, 0.02), 1e-6), "the magnet's size %s" % list(mags[0].dimensions))

if failures:
    raise RuntimeError("blender loader: %d checks failed: %s" % (len(failures), "; ".join(failures)))
print("blender loader: all checks passed")
