"""Runs inside Blender (its Python with `bpy`), never imported by kinema: builds the .blend of
a kinema USD stage, as `blend_writer.write_blend` asks. Its one argument (after `--` when
Blender runs it, `blender --background --python blender_scene.py -- JSON`) is a JSON object:

- `usd`: the stage (its folder is the .blend's), `blend`: the file to save,
- `fps`, `fps_base`: the scene's frame rate (Blender's rate is fps / fps_base),
- `frames`: the number of frames (the timeline is 0 … frames − 1, frame k the stage's time
  code k),
- `lo`, `hi`: the particles' extent over the run (m), which the camera frames.

What Blender's USD importer (5.0) leaves out and this adds: the scene's frame rate; a
material on the particles' point cloud, linked to the object (the importer's Mesh Sequence
Cache modifier gives the point cloud new data at every frame, which drops a material on the
data), whose Attribute node reads each point's `displayColor`; a material for the springs'
curves; a camera, a sun and a white world, so that a render shows the scene as kinema's videos do. The
colliders come from the stage as rendered meshes with their material (`UsdPreviewSurface`,
opacity 0.3). The cache file is saved relative to the .blend (`//run.usdc`): keep the two
together."""

import json
import math
import sys

import bpy
from mathutils import Vector

#: The view the camera looks from (from the scene towards the eye): in front (−y), a little
#: to the right and above, as a person sees a table.
VIEW = (0.35, -1.0, 0.6)
#: The camera's vertical field of view (degrees) and the margin around the particles.
FOV_DEG, MARGIN = 40.0, 1.15
#: The sun's strength (W/m²) and the world's light on the scene (its strength; the camera
#: sees it white).
SUN, AMBIENT = 2.5, 0.3
#: The springs' colour (linear RGB of kinema's videos' grey, sRGB 96 96 100).
SPRING_LINEAR = (0.117, 0.117, 0.127)


def main(job: dict) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.wm.usd_import(filepath=job["usd"], set_frame_range=True, import_guide=False)
    if "FINISHED" not in result:
        raise SystemExit(f"Blender could not import {job['usd']}")
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = int(job["fps"]), float(job["fps_base"])
    # the timeline stays the stage's range, which the import set: its first and last frames
    # with particles (an emitter's empty frame 0 left out: Blender aborts exporting a point
    # cloud of no points), frame k at time code k
    particles = particles_material()
    springs = flat_material("kinema springs", SPRING_LINEAR)
    for ob in scene.objects:
        if ob.type == "POINTCLOUD" and ob.name == "spheres":
            # the spin's PointInstancer: its striped balls sit where the coloured points are;
            # shown in the viewport, left out of renders (unhide it to see the balls roll)
            ob.hide_render = True
        elif ob.type == "POINTCLOUD":
            link(ob, particles)
        elif ob.type == "CURVES":
            link(ob, springs)
    lo, hi = Vector(job["lo"]), Vector(job["hi"])
    camera(scene, lo, hi)
    light(scene)
    for cache in bpy.data.cache_files:  # beside the .blend: the two move together
        cache.filepath = "//" + bpy.path.basename(cache.filepath)
    scene.frame_set(scene.frame_start)
    bpy.ops.wm.save_as_mainfile(filepath=job["blend"], relative_remap=False, compress=False)


def particles_material() -> bpy.types.Material:
    """Principled BSDF whose Base Color is the point's `displayColor` (linear RGB)."""
    material = bpy.data.materials.new("kinema particles")
    tree = material.node_tree
    bsdf = tree.nodes["Principled BSDF"]
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type, attribute.attribute_name = "GEOMETRY", "displayColor"
    attribute.location = (-300, 200)
    tree.links.new(attribute.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.5
    return material


def flat_material(name: str, colour: tuple) -> bpy.types.Material:
    material = bpy.data.materials.new(name)
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*colour, 1.0)
    return material


def link(ob: bpy.types.Object, material: bpy.types.Material) -> None:
    """`material` in the object's first slot, linked to the object, not its data: the
    cache modifier's data of each frame has no materials."""
    if not ob.material_slots:
        ob.data.materials.append(None)
    slot = ob.material_slots[0]
    slot.link = "OBJECT"
    slot.material = material


def camera(scene: bpy.types.Scene, lo: Vector, hi: Vector) -> None:
    """A camera looking from `VIEW` at the centre of the box [lo, hi], far enough that the
    box's bounding sphere fits the narrower field of view."""
    data = bpy.data.cameras.new("kinema camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(FOV_DEG)
    ob = bpy.data.objects.new("kinema camera", data)
    scene.collection.objects.link(ob)
    scene.camera = ob
    centre, radius = (lo + hi) / 2, max((hi - lo).length / 2, 1e-3)
    aspect = scene.render.resolution_x / scene.render.resolution_y
    half = math.radians(FOV_DEG) / 2
    narrow = half if aspect >= 1 else math.atan(math.tan(half) * aspect)
    distance = MARGIN * radius / math.sin(narrow)
    ob.location = centre + Vector(VIEW).normalized() * distance
    ob.rotation_euler = (centre - ob.location).to_track_quat("-Z", "Y").to_euler()
    data.clip_start, data.clip_end = distance / 1000, distance * 100


def light(scene: bpy.types.Scene) -> None:
    """A sun from above the camera's side; a world white where the camera sees it (kinema's
    videos' background) that lights the scene at `AMBIENT`; the Standard view transform
    (sRGB: a colour renders as kinema's videos draw it, not through AgX's tone curve)."""
    sun = bpy.data.lights.new("kinema sun", "SUN")
    sun.energy = SUN
    ob = bpy.data.objects.new("kinema sun", sun)
    scene.collection.objects.link(ob)
    ob.rotation_euler = (math.radians(35), 0.0, math.radians(20))
    world = bpy.data.worlds.new("kinema world")
    world.color = (1.0, 1.0, 1.0)
    tree = world.node_tree
    seen = tree.nodes["Background"]
    seen.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    lighting = tree.nodes.new("ShaderNodeBackground")
    lighting.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    lighting.inputs["Strength"].default_value = AMBIENT
    path, mix = tree.nodes.new("ShaderNodeLightPath"), tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    tree.links.new(lighting.outputs["Background"], mix.inputs[1])
    tree.links.new(seen.outputs["Background"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], tree.nodes["World Output"].inputs["Surface"])
    scene.world = world
    scene.view_settings.view_transform = "Standard"


if __name__ == "__main__":
    main(json.loads(sys.argv[-1]))
