"""Exports a purkinje scene's eyes, lights and one camera to Blender and
renders them with Cycles, an independent path tracer, for checking the
renderer's radiance (docs/rendering.md, "Against an independent renderer").

    PYTHONPATH=build/release/python blender -b --python scripts/blender_export.py -- \\
        SCENE OUT.exr [--camera NAME] [--samples N] [--pixel-filter box|gaussian|blackman-harris]
        [--pixel-filter-width W] [--blend FILE]

OUT.exr holds Cycles' radiance (the Combined pass, linear, W m^-2 sr^-1
when Cycles' point light of power 4 pi I emits I W/sr), to compare with the
Y plane of `purkinje render --no-noise`'s EXR. What is exported, exactly as
purkinje builds it (renderer/src/scene_geometry.cpp): the anterior cornea
up to the limbus and the posterior one down to the iris plane as finely
tessellated conicoids with their exact normals (smooth shading), glass of
the eye's indices; the iris annulus and the pupil's dark disc; the sclera's
sphere and the band that joins it to the limbus, diffuse on the outside and
black inside (purkinje's sclera has no inner albedo); lights as spheres of
the LED's emitting diameter (Cycles' MNEE finds the light through the
cornea: the corneas cast caustics, the iris receives them). Scenes with
lids, meshes, a textured iris or lens distortion are refused: the check is
of the eye's optics, on scenes built for it.
"""

import argparse
import math
import sys

import bpy
import numpy as np

import purkinje

# Blender units are mm, as the scene's: at the eye's size in metres Cycles'
# MNEE finds no path (its tolerances are absolute) and the iris stays black.
MM = 1.0
# Light power scaled so that radiance comes out per m^2, as purkinje's does.
PER_SQUARE_METRE = 1e6


def refuse(why):
    sys.exit(f"blender_export: {why}")


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_export.py")
    p.add_argument("scene")
    p.add_argument("output")
    p.add_argument("--camera", default=None)
    p.add_argument("--samples", type=int, default=1024)
    p.add_argument("--pixel-filter", default="box", choices=["box", "gaussian", "blackman-harris"])
    p.add_argument("--pixel-filter-width", type=float, default=0.0)
    p.add_argument("--blend", default=None, help="also save the .blend file here")
    return p.parse_args(argv)


def sag(radius, asphericity, r):
    """Depth below the apex of the conicoid x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0 at r."""
    return r * r / (radius + math.sqrt(radius * radius - (1 + asphericity) * r * r))


def surface_of_revolution(name, profile, material, world_from_eye, azimuths=720):
    """A mesh of rings about the eye's axis: `profile` lists (r, z, normal_r,
    normal_z) from one end to the other; each face is wound so that its
    normal points along the profile's, and the vertices carry the exact
    normals (smooth shading)."""
    prof = np.array(profile, dtype=float)
    phi = np.linspace(0, 2 * math.pi, azimuths, endpoint=False)
    c, s = np.cos(phi), np.sin(phi)
    r, z = prof[:, 0:1], prof[:, 1:2]
    vertices = np.stack([r * c, r * s, np.broadcast_to(z, r.shape[:1] + c.shape)], axis=-1).reshape(-1, 3) * MM
    normals = np.stack([prof[:, 2:3] * c, prof[:, 2:3] * s, np.broadcast_to(prof[:, 3:4], (len(prof), azimuths))],
                       axis=-1).reshape(-1, 3)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    i = np.arange(len(prof) - 1)[:, None]
    j = np.arange(azimuths)[None, :]
    a, b = i * azimuths + j, i * azimuths + (j + 1) % azimuths
    cc, d = a + azimuths, b + azimuths
    # (a, c, d, b) faces (-dz, dr) in the (r, z) plane, (a, b, d, c) the other way.
    tangent = prof[1:, :2] - prof[:-1, :2]
    along = (-tangent[:, 1] * prof[:-1, 2] + tangent[:, 0] * prof[:-1, 3])[:, None] > 0
    faces = np.where(along[..., None], np.stack([a, cc, d, b], -1), np.stack([a, b, d, cc], -1)).reshape(-1, 4)

    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.ravel())
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", faces.ravel().astype(np.int32))
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 4, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(faces), 4, dtype=np.int32))
    mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), dtype=bool))
    mesh.update()
    mesh.use_auto_smooth = True
    mesh.normals_split_custom_set_from_vertices(normals)
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    obj.matrix_world = world_from_eye
    bpy.context.scene.collection.objects.link(obj)
    return obj


def conicoid_profile(radius, asphericity, apex_z, r_max, rings):
    """The cap from its apex out to r_max, normals out of the eye (+z)."""
    k = 1 + asphericity
    out = []
    for i in range(rings + 1):
        r = r_max * (i / rings) ** 0.75 if i else 0.0  # denser near the rim, where rays graze
        w = sag(radius, asphericity, r)
        # Gradient of x^2 + y^2 + k w^2 - 2 R w with w = apex_z - z: (r, -(k w - R)) in (r, z).
        out.append((r, apex_z - w, r, radius - k * w))
    return out


def material(name, albedo=None, ior=None, black_inside=False):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    if ior is not None:
        bsdf = nodes.new("ShaderNodeBsdfGlass")
        bsdf.distribution = "SHARP"
        bsdf.inputs["IOR"].default_value = ior
        bsdf.inputs["Color"].default_value = (1, 1, 1, 1)
        links.new(bsdf.outputs[0], output.inputs["Surface"])
        return m
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (albedo, albedo, albedo, 1)
    bsdf.inputs["Roughness"].default_value = 0.0  # Lambertian
    if not black_inside:
        links.new(bsdf.outputs[0], output.inputs["Surface"])
        return m
    geometry = nodes.new("ShaderNodeNewGeometry")
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0, 0, 0, 1)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs[0])
    links.new(bsdf.outputs[0], mix.inputs[1])
    links.new(black.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    return m


def export_eye(eye, appearance):
    m = eye.model
    if appearance.get("iris_texture_contrast", 0.5) != 0:
        refuse("a textured iris: set appearance.iris_texture_contrast to 0")
    for key in ("skin_texture_contrast", "sclera_vessel_contrast"):
        if appearance.get(key, 0) != 0:
            refuse(f"a textured skin or sclera: set appearance.{key} to 0")
    if "tear_film" in appearance:
        refuse("a wet sclera (its highlights are drawn explicitly): remove appearance.tear_film")
    world_from_eye = np.array(eye.world_from_eye)
    matrix = np.eye(4)
    matrix[:3, :3] = world_from_eye[:3, :3]
    matrix[:3, 3] = world_from_eye[:3, 3] * MM
    import mathutils
    world = mathutils.Matrix(matrix.tolist())

    R, Q = m.cornea_radius_mm, m.cornea_asphericity
    limbus = m.limbus_radius_mm
    d_limbus = sag(R, Q, limbus)
    back = m.posterior_cornea
    n_front = back["index"] if back else m.aqueous_index
    front = surface_of_revolution("cornea_anterior", conicoid_profile(R, Q, R, limbus, 400),
                                  material("cornea_anterior", ior=n_front), world)
    casters = [front]
    if back:
        depth = max(d_limbus, m.iris_depth_mm) - back["thickness_mm"]
        r_back = math.sqrt(2 * back["radius_mm"] * depth - (1 + back["asphericity"]) * depth * depth)
        casters.append(surface_of_revolution(
            "cornea_posterior",
            conicoid_profile(back["radius_mm"], back["asphericity"], R - back["thickness_mm"], r_back, 400),
            material("cornea_posterior", ior=m.aqueous_index / back["index"]), world))
    for obj in casters:
        obj.cycles.is_caustics_caster = True

    # The shell: sphere about the centre of rotation, joined to the limbus by
    # a band (cylinder) or an annulus in the limbus plane.
    sclera = material("sclera", albedo=appearance.get("sclera_albedo", 0.55), black_inside=True)
    Rs, z_c, z_l = m.sclera_radius_mm, R - m.rotation_center_depth_mm, R - d_limbus
    h = z_l - z_c
    if Rs >= limbus and math.sqrt(Rs * Rs - limbus * limbus) < h:
        z_seam = z_c + math.sqrt(Rs * Rs - limbus * limbus)
        surface_of_revolution("limbal_band", [(limbus, z_l, 1, 0), (limbus, z_seam, 1, 0)], sclera, world)
    else:
        z_seam = z_l
        rho = math.sqrt(Rs * Rs - h * h)
        surface_of_revolution("limbal_annulus", [(min(rho, limbus), z_l, 0, 1), (max(rho, limbus), z_l, 0, 1)],
                              sclera, world)
    top = math.asin((z_seam - z_c) / Rs)
    steps = 200
    profile = []
    for i in range(steps + 1):
        a = top - (top + math.pi / 2) * i / steps
        profile.append((Rs * math.cos(a), z_c + Rs * math.sin(a), math.cos(a), math.sin(a)))
    surface_of_revolution("sclera", profile, sclera, world)

    # Iris (annulus about the decentred pupil) and pupil (dark disc).
    z_i = R - m.iris_depth_mm
    dx, dy = m.pupil_decentration_mm
    if dx or dy:
        refuse("a decentred pupil is not exported yet")
    iris_mat = material("iris", albedo=appearance.get("iris_albedo", 0.35))
    rp, ro = m.pupil_radius_mm, m.iris_outer_radius_mm
    iris = surface_of_revolution("iris", [(rp + (ro - rp) * i / 80, z_i, 0, 1) for i in range(81)], iris_mat, world)
    iris.cycles.is_caustics_receiver = True
    surface_of_revolution("pupil", [(rp * i / 20, z_i, 0, 1) for i in range(21)], material("pupil", albedo=0.0),
                          world)


def main():
    args = arguments()
    scene = purkinje.load_scene(args.scene)
    spec = scene.to_dict()
    for key in ("meshes",):
        if spec.get(key):
            refuse(f"the scene has {key}")
    cameras = scene.cameras
    camera = next((c for c in cameras if args.camera in (None, c.name)), None)
    if camera is None:
        refuse(f"no camera {args.camera!r}")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    b = bpy.context.scene
    b.render.engine = "CYCLES"
    b.cycles.device = "CPU"
    b.cycles.samples = args.samples
    b.cycles.use_adaptive_sampling = False
    b.cycles.use_denoising = False
    b.cycles.sample_clamp_direct = 0
    b.cycles.sample_clamp_indirect = 0
    b.cycles.max_bounces = 32
    b.cycles.diffuse_bounces = 4
    b.cycles.glossy_bounces = 16
    b.cycles.transmission_bounces = 16
    b.cycles.caustics_reflective = True
    b.cycles.caustics_refractive = True
    b.cycles.pixel_filter_type = {"box": "BOX", "gaussian": "GAUSSIAN", "blackman-harris": "BLACKMAN_HARRIS"}[
        args.pixel_filter]
    b.cycles.filter_width = args.pixel_filter_width or (1.0 if args.pixel_filter == "box" else 3.0)
    b.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0, 0, 0)
    b.world = world

    for eye, eye_spec in zip(scene.eyes, spec["eyes"]):
        if eye_spec.get("eyelids") is not None:
            refuse("an eye with lids: leave eyelids out")
        export_eye(eye, eye_spec.get("appearance", {}))

    for light in scene.illuminators:
        data = bpy.data.lights.new(light.name, "POINT")
        data.energy = 4 * math.pi * light.radiant_intensity_w_sr * PER_SQUARE_METRE
        data.shadow_soft_size = 0.5 * light.emitter_diameter_mm * MM
        data.cycles.is_caustics_light = True
        obj = bpy.data.objects.new(light.name, data)
        obj.location = tuple(np.array(light.position_mm) * MM)
        b.collection.objects.link(obj)

    # The camera: OpenCV's frame (x right, y down, z ahead) to Blender's (x
    # right, y up, looking down -z); the principal point by the lens shift.
    if any(abs(v) > 0 for v in np.ravel(camera.distortion)):
        refuse("a camera with lens distortion")
    width, height = camera.resolution_px
    k = np.array(camera.camera_matrix)
    pose = np.array(camera.world_from_camera)
    import mathutils
    matrix = np.eye(4)
    matrix[:3, :3] = pose[:3, :3] @ np.diag([1.0, -1.0, -1.0])
    matrix[:3, 3] = pose[:3, 3] * MM
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "HORIZONTAL"
    cam.sensor_width = 36.0
    cam.lens = k[0, 0] / width * 36.0  # fx in px over the width in px, times the sensor width
    cam.shift_x = ((width - 1) / 2 - k[0, 2]) / max(width, height)
    cam.shift_y = (k[1, 2] - (height - 1) / 2) / max(width, height)
    cam.clip_start = 1 * MM
    cam.clip_end = 1e5 * MM
    obj = bpy.data.objects.new("camera", cam)
    obj.matrix_world = mathutils.Matrix(matrix.tolist())
    b.collection.objects.link(obj)
    b.camera = obj
    b.render.resolution_x, b.render.resolution_y = width, height
    b.render.resolution_percentage = 100
    b.render.pixel_aspect_x = b.render.pixel_aspect_y = 1
    if abs(k[0, 0] - k[1, 1]) > 1e-9 * k[0, 0]:
        refuse("non-square pixels")

    b.render.image_settings.file_format = "OPEN_EXR"
    b.render.image_settings.color_depth = "32"
    b.render.image_settings.exr_codec = "ZIP"
    b.render.filepath = args.output
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=args.blend)
    bpy.ops.render.render(write_still=True)


main()
