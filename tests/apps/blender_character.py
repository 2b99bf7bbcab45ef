# A character made in Blender (background mode), exported as an animator would export it, with Blender's own
# skinning of it as the answer to compare with (tests/rig/test_model_formats.cpp).
#   blender -b --factory-startup --python-exit-code 1 -P blender_character.py -- OUTDIR
# Writes OUTDIR/character.glb (glTF exporter), character.fbx (FBX exporter, its default axes and units),
# character_zup.fbx (the same, Z up), character.dae (COLLADA exporter), character_prop.glb/.fbx (with a cube
# parented to the hand bone; truth_prop.json holds its vertices per frame) and truth.json: per frame of the clip (1, 12, 24 at 24 fps) the evaluated
# skin's vertices in Blender's world, and the bones' heads at frame 1.
# The character: a bent arm of three bones (upper, lower, hand) inside a closed tube of 16 sides and 24 rings,
# with smooth weights across the elbow and the wrist, smooth shading and a UV map; the elbow bends 70° and the
# wrist 30° over the clip. truth.json also holds the evaluated skin's vertex normals at frame 1.
import json
import math
import os
import sys

import bpy
from mathutils import Matrix

out = sys.argv[sys.argv.index("--") + 1]
os.makedirs(out, exist_ok=True)

bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start, scene.frame_end = 1, 24

# The path of the arm: heads of upper, lower, hand and the hand's tail (not on one line).
points = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.5), (0.0, 0.2, 0.95), (0.0, 0.3, 1.15)]


def along(s):
    """The point at arc parameter s in [0, 3] (one unit per bone) and the bone's direction."""
    b = min(int(s), 2)
    f = s - b
    p, q = points[b], points[b + 1]
    return tuple(p[i] + f * (q[i] - p[i]) for i in range(3)), b, f


rings, sides, radius = 24, 16, 0.08
verts, faces, weights = [], [], []
for r in range(rings + 1):
    s = 3.0 * r / rings
    c, b, f = along(s)
    # A frame across the path: x, and y × direction.
    p, q = points[b], points[b + 1]
    d = [q[i] - p[i] for i in range(3)]
    n = math.sqrt(sum(x * x for x in d))
    d = [x / n for x in d]
    u = (1.0, 0.0, 0.0)
    v = (d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0])
    rr = radius * (1.0 - 0.15 * s / 3.0)
    for k in range(sides):
        a = 2.0 * math.pi * k / sides
        verts.append(tuple(c[i] + rr * (math.cos(a) * u[i] + math.sin(a) * v[i]) for i in range(3)))
        # Weights: each bone near its middle, blended over ±0.3 of a bone at the joints.
        w = [0.0, 0.0, 0.0]
        for j in range(3):
            w[j] = max(0.0, 1.0 - max(0.0, abs(s - (j + 0.5)) - 0.2) / 0.5)
        t = sum(w)
        weights.append([x / t for x in w])
for r in range(rings):
    for k in range(sides):
        a, b = r * sides + k, r * sides + (k + 1) % sides
        faces.append((a, b, b + sides, a + sides))
bottom = len(verts)
verts.append(points[0])
weights.append([1.0, 0.0, 0.0])
top = len(verts)
verts.append(along(3.0)[0])
weights.append([0.0, 0.0, 1.0])
for k in range(sides):
    faces.append((bottom, (k + 1) % sides, k))
    faces.append((top, rings * sides + k, rings * sides + (k + 1) % sides))

mesh = bpy.data.meshes.new("arm")
mesh.from_pydata(verts, [], faces)
# Smooth shading and a cylindrical UV map with a seam where the sides close, as a character's skin has them.
uv = mesh.uv_layers.new(name="UVMap")
for poly in mesh.polygons:
    poly.use_smooth = True
    ring = [v for v in poly.vertices if v < bottom]
    wraps = any(v % sides == sides - 1 for v in ring) and any(v % sides == 0 for v in ring)
    for li in poly.loop_indices:
        v = mesh.loops[li].vertex_index
        if v >= bottom:  # a cap's centre
            uv.data[li].uv = (0.5, 0.0 if v == bottom else 1.0)
            continue
        r, k = divmod(v, sides)
        uv.data[li].uv = (1.0 if (wraps and k == 0) else k / sides, r / rings)
mesh.update()
body = bpy.data.objects.new("arm", mesh)
scene.collection.objects.link(body)

armature = bpy.data.armatures.new("rig")
rig = bpy.data.objects.new("rig", armature)
scene.collection.objects.link(rig)
bpy.context.view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
names = ["upper", "lower", "hand"]
parent = None
for j, name in enumerate(names):
    e = armature.edit_bones.new(name)
    e.head, e.tail = points[j], points[j + 1]
    if parent is not None:
        e.parent = parent
        e.use_connect = True
    parent = e
bpy.ops.object.mode_set(mode="OBJECT")

for j, name in enumerate(names):
    g = body.vertex_groups.new(name=name)
    for i, w in enumerate(weights):
        if w[j] > 0.0:
            g.add([i], w[j], "REPLACE")
body.parent = rig
modifier = body.modifiers.new("rig", "ARMATURE")
modifier.object = rig

# The clip: the elbow bends 70° and the wrist 30° about the bones' own x axes, keyed at 1, 12 and 24.
bpy.ops.object.mode_set(mode="POSE")
for frame, elbow, wrist in [(1, 0.0, 0.0), (12, 40.0, 10.0), (24, 70.0, 30.0)]:
    for name, angle in [("lower", elbow), ("hand", wrist)]:
        pb = rig.pose.bones[name]
        pb.rotation_mode = "QUATERNION"
        pb.rotation_quaternion = (math.cos(math.radians(angle) / 2), math.sin(math.radians(angle) / 2), 0.0, 0.0)
        pb.keyframe_insert("rotation_quaternion", frame=frame)
bpy.ops.object.mode_set(mode="OBJECT")
rig.animation_data.action.name = "bend"

truth = {"frames": {}, "fps": 24, "first_frame": 1}
for frame in (1, 12, 24):
    scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = body.evaluated_get(depsgraph)
    m = evaluated.to_mesh()
    truth["frames"][str(frame)] = [list(body.matrix_world @ v.co) for v in m.vertices]
    evaluated.to_mesh_clear()
scene.frame_set(1)
depsgraph = bpy.context.evaluated_depsgraph_get()
evaluated = body.evaluated_get(depsgraph)
m = evaluated.to_mesh()
truth["normals"] = [list(v.normal) for v in m.vertices]
evaluated.to_mesh_clear()
truth["heads"] = {name: list(rig.matrix_world @ rig.data.bones[name].head_local) for name in names}
with open(os.path.join(out, "truth.json"), "w") as f:
    json.dump(truth, f)


def export(name):
    """Everything, as NAME.glb (glTF exporter) and NAME.fbx (FBX exporter, its default axes and units)."""
    bpy.ops.object.select_all(action="SELECT")
    bpy.ops.export_scene.gltf(filepath=os.path.join(out, name + ".glb"), export_format="GLB", export_animations=True,
                              export_skins=True)
    bpy.ops.export_scene.fbx(filepath=os.path.join(out, name + ".fbx"), bake_anim=True, add_leaf_bones=False)


export("character")
# The same with Blender's own axes kept (Z up), as some pipelines ask for.
bpy.ops.export_scene.fbx(filepath=os.path.join(out, "character_zup.fbx"), bake_anim=True, add_leaf_bones=False,
                         axis_up="Z", axis_forward="Y")
bpy.ops.wm.collada_export(filepath=os.path.join(out, "character.dae"), include_animations=True)

# A prop without a skin: a small cube parented to the hand bone, exported again as character_prop.glb and
# character_prop.fbx; truth_prop.json holds its vertices in Blender's world per frame.
bpy.ops.object.select_all(action="DESELECT")
bpy.ops.mesh.primitive_cube_add(size=0.06, location=(0.0, 0.3, 1.0))
prop = bpy.context.active_object
prop.name = "prop"
prop.parent = rig
prop.parent_type = "BONE"
prop.parent_bone = "hand"
prop.matrix_parent_inverse = (rig.matrix_world @ rig.pose.bones["hand"].matrix @ Matrix.Translation((0.0, rig.data.bones["hand"].length, 0.0))).inverted()
prop_truth = {"frames": {}}
for frame in (1, 12, 24):
    scene.frame_set(frame)
    prop_truth["frames"][str(frame)] = [list(prop.matrix_world @ v.co) for v in prop.data.vertices]
scene.frame_set(1)
with open(os.path.join(out, "truth_prop.json"), "w") as f:
    json.dump(prop_truth, f)
export("character_prop")
print("blender_character: wrote", out)
