"""Run a Lodestone scene and load the result into Blender.

Inside Blender (Scripting workspace, or `blender --python blender_run_scene.py
-- SCENE.json OUT_DIR`), with the lodestone module on Blender's Python path
(the module must be built for Blender's Python version; see docs/python.md):
the scene is simulated, each frame's particles are written as a .vdb point
file, and the last frame's particles are loaded as a mesh of vertices
"lodestone_particles" with a per-point attribute n_p.

Outside Blender the same script simulates and writes the files only:

    PYTHONPATH=build/python python3 python/examples/blender_run_scene.py SCENE.json OUT_DIR [FRAMES]
"""
import os
import sys

import lodestone


def simulate(scene_path, out_dir, frames=0, dx=0.0):
    """Runs the scene; writes particles_NNNN.vdb per frame. Returns the list of (frame, particle file)."""
    os.makedirs(out_dir, exist_ok=True)
    scene = lodestone.Scene.load(scene_path, dx=dx)
    written = []

    def on_frame(frame, solver):
        particles = os.path.join(out_dir, f"particles_{frame:04d}.vdb")
        lodestone.write_particles_vdb(particles, solver, frame)
        written.append((frame, particles))
        print(f"frame {frame}: t = {solver.time:.4f} s, {solver.particle_count} particles -> {particles}")

    scene.run(frames=frames, on_frame=on_frame)
    return written


def load_into_blender(particle_file):
    """Loads a particle .vdb into Blender as a mesh of vertices (one per particle)."""
    import bpy  # only inside Blender

    data = lodestone.read_particles_vdb(particle_file)
    mesh = bpy.data.meshes.new("lodestone_particles")
    mesh.from_pydata([tuple(p) for p in data["positions"]], [], [])
    attr = mesh.attributes.new("n_p", "FLOAT", "POINT")
    attr.data.foreach_set("value", data["counts"].astype("float32"))
    obj = bpy.data.objects.new("lodestone_particles", mesh)
    bpy.context.collection.objects.link(obj)
    return obj


def main(argv):
    args = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    if len(args) < 2:
        print(__doc__)
        return 2
    frames = int(args[2]) if len(args) > 2 else 0
    written = simulate(args[0], args[1], frames)
    try:
        import bpy  # noqa: F401
    except ImportError:
        return 0  # not inside Blender: the files are the result
    load_into_blender(written[-1][1])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
