"""Run by Blender (blender --background --python blender_pc2.py -- RUN_DIR): loads a flesh run's point caches
(flesh.pc2, lbs.pc2) into Blender's own Mesh Cache modifier on the model's mesh (built from frame 0's OBJ, in
the model's vertex order) and compares the evaluated vertices at every frame with the OBJ frames. Prints one
line per cache; exits 1 on a mismatch."""
import pathlib
import sys

import bpy


def read_obj(path):
    verts, faces = [], []
    for line in pathlib.Path(path).read_text().splitlines():
        if line.startswith("v "):
            verts.append(tuple(float(c) for c in line.split()[1:4]))
        elif line.startswith("f "):
            faces.append(tuple(int(c.split("/")[0]) - 1 for c in line.split()[1:]))
    return verts, faces


def main():
    run = pathlib.Path(sys.argv[sys.argv.index("--") + 1])
    failed = False
    for cache, folder in (("flesh.pc2", "surface"), ("lbs.pc2", "lbs")):
        frames = sorted((run / folder).glob("*.obj"))
        verts, faces = read_obj(frames[0])
        mesh = bpy.data.meshes.new(folder)
        mesh.from_pydata(verts, [], faces)
        obj = bpy.data.objects.new(folder, mesh)
        bpy.context.scene.collection.objects.link(obj)
        mod = obj.modifiers.new("cache", "MESH_CACHE")
        mod.cache_format = "PC2"
        mod.filepath = str(run / cache)
        mod.frame_start = 0.0
        size = max(max(v[k] for v in verts) - min(v[k] for v in verts) for k in range(3))
        worst = 0.0
        for k, frame in enumerate(frames):
            bpy.context.scene.frame_set(k)
            evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
            expected, _ = read_obj(frame)
            if len(evaluated.vertices) != len(expected):
                print(f"{cache}: frame {k}: Blender has {len(evaluated.vertices)} vertices, the OBJ {len(expected)}")
                failed = True
                break
            for v, e in zip(evaluated.vertices, expected):
                worst = max(worst, max(abs(v.co[i] - e[i]) for i in range(3)))
        ok = worst <= 1e-6 * size
        failed = failed or not ok
        print(f"{cache}: {len(frames)} frames in Blender's Mesh Cache modifier, largest difference from the OBJ frames "
              f"{worst:.3g} ({worst / size:.2g} of the model's size): {'ok' if ok else 'MISMATCH'}")
        # the frames must differ from each other, or the comparison proves nothing
        if read_obj(frames[0])[0] == read_obj(frames[-1])[0]:
            print(f"{cache}: the first and last frames are the same: nothing was compared")
            failed = True
    sys.exit(1 if failed else 0)


main()
