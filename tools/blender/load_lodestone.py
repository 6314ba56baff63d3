"""Loads a `lodestone run` output directory into Blender (3.4 or later).

    blender --python tools/blender/load_lodestone.py -- RUN_DIR [--scene SCENE.json] [--save OUT.blend]

or, from Blender's Python console / another script:

    import load_lodestone; load_lodestone.load_run("/path/to/run")

What it loads, each as one collection under "Lodestone <run>":
  * mesh_NNNN.obj (or mesh_NNNN.ply): one object per frame, shown only on
    its frame (hide_viewport / hide_render keyed), with a glossy dark
    material (the paper's ferrofluid look);
  * volume_NNNN.vdb: one Volume object reading the files as a sequence
    (frame_start = the first file's number), with a Principled Volume
    reading the `density` grid and emission driven by `magnetization`;
  * field_lines_NNNN.obj: curves (one poly spline per `l` line) per frame,
    shown only on their frame, with an emissive material;
  * the magnets of the scene file (--scene, else the one named by
    lodestone_run.json when it can be found): spheres, boxes and cylinders
    at their initial pose, keyed along their motion keyframes.
The scene's frame range and fps (from the scene file, else 24) are set.
Units: Lodestone writes metres; Blender's unit is the metre.
"""
import json
import math
import os
import re
import sys

import bpy

FRAME_RE = re.compile(r"^(?P<stem>[a-z_]+)_(?P<frame>\d{4,})\.(?P<ext>obj|ply|vdb)$")


def frame_files(run_dir, stem, exts):
    """{frame: path} of RUN_DIR/stem_NNNN.ext, the first extension in `exts` that exists per frame."""
    found = {}
    for name in sorted(os.listdir(run_dir)):
        m = FRAME_RE.match(name)
        if not m or m.group("stem") != stem or m.group("ext") not in exts:
            continue
        frame = int(m.group("frame"))
        prev = found.get(frame)
        if prev is None or exts.index(m.group("ext")) < exts.index(os.path.splitext(prev)[1][1:]):
            found[frame] = os.path.join(run_dir, name)
    return found


def show_only_on(obj, frame):
    """Keys obj visible on `frame` only (constant interpolation)."""
    for f, hidden in ((frame - 1, True), (frame, False), (frame + 1, True)):
        obj.hide_viewport = hidden
        obj.hide_render = hidden
        obj.keyframe_insert("hide_viewport", frame=f)
        obj.keyframe_insert("hide_render", frame=f)
    if obj.animation_data and obj.animation_data.action:
        for fc in obj.animation_data.action.fcurves:
            for k in fc.keyframe_points:
                k.interpolation = "CONSTANT"


def material_surface():
    mat = bpy.data.materials.get("lodestone_surface") or bpy.data.materials.new("lodestone_surface")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf:
        bsdf.inputs["Base Color"].default_value = (0.02, 0.02, 0.025, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.15
        bsdf.inputs["Specular"].default_value = 0.8
    return mat


def material_volume():
    mat = bpy.data.materials.get("lodestone_volume") or bpy.data.materials.new("lodestone_volume")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    for n in list(nodes):
        nodes.remove(n)
    out = nodes.new("ShaderNodeOutputMaterial")
    vol = nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density Attribute"].default_value = "density"
    vol.inputs["Density"].default_value = 50.0
    vol.inputs["Color"].default_value = (0.05, 0.05, 0.06, 1.0)
    mag = nodes.new("ShaderNodeAttribute")
    mag.attribute_name = "magnetization"
    scale = nodes.new("ShaderNodeMath")
    scale.operation = "MULTIPLY"
    scale.inputs[1].default_value = 1e-6  # A/m to a usable emission strength
    links.new(mag.outputs["Fac"], scale.inputs[0])
    links.new(scale.outputs["Value"], vol.inputs["Emission Strength"])
    vol.inputs["Emission Color"].default_value = (1.0, 0.45, 0.1, 1.0)
    links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return mat


def material_lines():
    mat = bpy.data.materials.get("lodestone_field_lines") or bpy.data.materials.new("lodestone_field_lines")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf:
        bsdf.inputs["Emission"].default_value = (1.0, 0.6, 0.15, 1.0)
        bsdf.inputs["Emission Strength"].default_value = 2.0
    return mat


def import_mesh(path):
    """The object of one OBJ or PLY mesh file."""
    before = set(bpy.data.objects)
    if path.endswith(".obj"):
        bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
    else:
        bpy.ops.import_mesh.ply(filepath=path)
    new = [o for o in bpy.data.objects if o not in before]
    if not new:
        raise RuntimeError("no object imported from " + path)
    return new[0]


def read_obj_lines(path):
    """Vertices and `l` polylines (0-based) of a field-line OBJ file."""
    verts, lines = [], []
    with open(path) as f:
        for row in f:
            if row.startswith("v "):
                verts.append(tuple(float(t) for t in row.split()[1:4]))
            elif row.startswith("l "):
                lines.append([int(t.split("/")[0]) - 1 for t in row.split()[1:]])
    return verts, lines


def field_line_object(path, name, collection):
    verts, lines = read_obj_lines(path)
    curve = bpy.data.curves.new(name, type="CURVE")
    curve.dimensions = "3D"
    curve.bevel_depth = 0.0005  # m: visible in renders
    for idx in lines:
        closed = len(idx) > 2 and idx[0] == idx[-1]
        pts = idx[:-1] if closed else idx
        spline = curve.splines.new("POLY")
        spline.points.add(len(pts) - 1)
        for p, i in zip(spline.points, pts):
            p.co = (*verts[i], 1.0)
        spline.use_cyclic_u = closed
    curve.materials.append(material_lines())
    obj = bpy.data.objects.new(name, curve)
    collection.objects.link(obj)
    return obj


def load_scene_json(run_dir, scene_path):
    if scene_path is None:
        try:
            with open(os.path.join(run_dir, "lodestone_run.json")) as f:
                scene_path = json.load(f)["identity"]["scene_file"]
        except (OSError, KeyError, ValueError):
            return None
        for candidate in (scene_path, os.path.join(run_dir, scene_path)):
            if os.path.isfile(candidate):
                scene_path = candidate
                break
        else:
            return None
    with open(scene_path) as f:
        return json.load(f)


def axis_rotation(axis):
    """Euler angles turning +z onto `axis`."""
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z) or 1.0
    x, y, z = x / n, y / n, z / n
    return (math.atan2(-y, z) if abs(x) < 1 - 1e-12 else 0.0, math.asin(max(-1.0, min(1.0, x))), 0.0)


def add_magnets(scene, fps, collection):
    objs = []
    mat = bpy.data.materials.get("lodestone_magnet") or bpy.data.materials.new("lodestone_magnet")
    mat.diffuse_color = (0.77, 0.2, 0.18, 1.0)
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.77, 0.2, 0.18, 1.0)
    for k, m in enumerate(scene.get("magnets", [])):
        shape = m.get("shape", "box")
        centre = m.get("center", [0, 0, 0])
        if shape == "sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(radius=m["radius"], location=centre)
        elif shape == "cylinder":
            bpy.ops.mesh.primitive_cylinder_add(radius=m["radius"], depth=2 * m["half_length"], location=centre)
        else:
            bpy.ops.mesh.primitive_cube_add(size=2.0, location=centre)
            bpy.context.object.scale = m.get("half_size", [0.01, 0.01, 0.01])
        obj = bpy.context.object
        obj.name = "magnet_%d" % k
        obj.data.materials.append(mat)
        if "axis" in m:
            obj.rotation_euler = axis_rotation(m["axis"])
        for key in m.get("motion", {}).get("keyframes", []):
            frame = key["time"] * fps
            if "center" in key:
                obj.location = key["center"]
                obj.keyframe_insert("location", frame=frame)
            if "axis" in key:
                obj.rotation_euler = axis_rotation(key["axis"])
                obj.keyframe_insert("rotation_euler", frame=frame)
        for c in list(obj.users_collection):
            c.objects.unlink(obj)
        collection.objects.link(obj)
        objs.append(obj)
    return objs


def load_run(run_dir, scene_path=None):
    """Loads RUN_DIR; returns {"meshes": [...], "volume": obj or None, "field_lines": [...], "magnets": [...]}."""
    run_dir = os.path.abspath(run_dir)
    if not os.path.isdir(run_dir):
        raise FileNotFoundError("not a directory: " + run_dir)
    name = os.path.basename(run_dir.rstrip("/"))
    root = bpy.data.collections.new("Lodestone " + name)
    bpy.context.scene.collection.children.link(root)
    scene = load_scene_json(run_dir, scene_path)
    fps = float(scene.get("time", {}).get("fps", 24)) if scene else 24.0
    bpy.context.scene.render.fps = int(round(fps))
    result = {"meshes": [], "volume": None, "field_lines": [], "magnets": []}
    frames = set()

    meshes = frame_files(run_dir, "mesh", ["obj", "ply"])
    if meshes:
        col = bpy.data.collections.new("surface")
        root.children.link(col)
        surface = material_surface()
        for frame, path in sorted(meshes.items()):
            obj = import_mesh(path)
            obj.name = "surface_%04d" % frame
            for c in list(obj.users_collection):
                c.objects.unlink(obj)
            col.objects.link(obj)
            obj.data.materials.clear()
            obj.data.materials.append(surface)
            show_only_on(obj, frame)
            result["meshes"].append(obj)
        frames.update(meshes)

    volumes = frame_files(run_dir, "volume", ["vdb"])
    if volumes:
        first = min(volumes)
        data = bpy.data.volumes.new("volume")
        data.filepath = volumes[first]
        if len(volumes) > 1:
            data.is_sequence = True
            data.frame_start = first
            data.frame_offset = first - 1  # the sequence's first file is the one numbered `first`
            data.frame_duration = max(volumes) - first + 1
            data.sequence_mode = "CLIP"
        data.materials.append(material_volume())
        obj = bpy.data.objects.new("volume", data)
        root.objects.link(obj)
        result["volume"] = obj
        frames.update(volumes)

    lines = frame_files(run_dir, "field_lines", ["obj"])
    if lines:
        col = bpy.data.collections.new("field lines")
        root.children.link(col)
        for frame, path in sorted(lines.items()):
            obj = field_line_object(path, "field_lines_%04d" % frame, col)
            show_only_on(obj, frame)
            result["field_lines"].append(obj)
        frames.update(lines)

    if scene:
        col = bpy.data.collections.new("magnets")
        root.children.link(col)
        result["magnets"] = add_magnets(scene, fps, col)

    if frames:
        bpy.context.scene.frame_start = min(frames)
        bpy.context.scene.frame_end = max(frames)
        bpy.context.scene.frame_set(min(frames))
    return result


def main(argv):
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    if not args or args[0].startswith("-"):
        print("usage: blender --python load_lodestone.py -- RUN_DIR [--scene SCENE.json] [--save OUT.blend]")
        return 2
    run_dir, scene, save = args[0], None, None
    i = 1
    while i < len(args):
        if args[i] == "--scene" and i + 1 < len(args):
            scene = args[i + 1]
            i += 2
        elif args[i] == "--save" and i + 1 < len(args):
            save = args[i + 1]
            i += 2
        else:
            print("load_lodestone: unknown argument " + args[i])
            return 2
    r = load_run(run_dir, scene)
    print("load_lodestone: %d mesh frames, %s, %d field-line frames, %d magnets from %s"
          % (len(r["meshes"]), "a volume sequence" if r["volume"] else "no volume", len(r["field_lines"]),
             len(r["magnets"]), run_dir))
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(save))
    return 0


if __name__ == "__main__":
    code = main(sys.argv)
    if code:
        sys.exit(code)
