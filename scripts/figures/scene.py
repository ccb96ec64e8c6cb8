"""Scene, camera, lights, Cycles settings, rendering and PNG composition (real bpy)."""
from __future__ import annotations

import math
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector


def reset_scene(width: int, height: int, samples: int):
    """Empty scene rendered by Cycles on the CPU, 8-bit PNG, 'Standard' view transform.

    'Standard' keeps authored colours: an emission of 1.0 is pure white, which
    the zebra renders need (AgX/Filmic would turn it grey).
    """
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.image_settings.file_format = "PNG"
    r.image_settings.color_depth = "8"
    r.image_settings.compression = 90
    r.film_transparent = False
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = max(1, int(samples))
    cy.use_adaptive_sampling = True
    cy.max_bounces, cy.diffuse_bounces, cy.glossy_bounces = 4, 2, 2
    cy.transmission_bounces, cy.transparent_max_bounces = 2, 4
    # OpenImageDenoise ships in the bpy wheel; denoising 1 sample is pointless.
    cy.use_denoising = cy.samples >= 4
    if cy.use_denoising:
        cy.denoiser = "OPENIMAGEDENOISE"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    return scene


def set_world(scene, colour=(0.8, 0.82, 0.86), strength=1.0, backdrop=None):
    """Uniform world light; the camera sees `backdrop` (RGB) instead when given."""
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes["Background"]
    bg.inputs["Color"].default_value = (*colour, 1.0)
    bg.inputs["Strength"].default_value = strength
    if backdrop is not None:
        seen = nt.nodes.new("ShaderNodeBackground")
        seen.inputs["Color"].default_value = (*backdrop, 1.0)
        path = nt.nodes.new("ShaderNodeLightPath")
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
        nt.links.new(bg.outputs["Background"], mix.inputs[1])
        nt.links.new(seen.outputs["Background"], mix.inputs[2])
        nt.links.new(mix.outputs["Shader"], nt.nodes["World Output"].inputs["Surface"])
    return world


def add_caption(scene, camera, text, material, height_frac=0.055, margin_frac=0.03, backing=None):
    """Text in the top-left corner of the frame, parented to the camera (flat, emissive).

    Placed 0.2 units in front of the camera, so it never touches the object;
    `backing` (a material) puts a box of it behind the text.
    """
    curve = bpy.data.curves.new("Caption", "FONT")
    curve.body = text
    curve.align_x, curve.align_y = "LEFT", "TOP"
    obj = bpy.data.objects.new("Caption", curve)
    curve.materials.append(material)
    scene.collection.objects.link(obj)
    w, h = scene.render.resolution_x, scene.render.resolution_y
    cam = camera.data
    depth = 0.2
    half_long = depth * 0.5 * cam.sensor_width / cam.lens
    half_w, half_h = (half_long, half_long * h / w) if w >= h else (half_long * w / h, half_long)
    size = 2.0 * half_h * height_frac
    m = 2.0 * half_h * margin_frac
    obj.parent = camera
    obj.location = (-half_w + m, half_h - m, -depth)
    obj.scale = (size, size, size)
    cam.clip_start = min(cam.clip_start, 0.5 * depth)
    if backing is not None:
        # a plain box behind the text, so it stays legible over the object
        bpy.context.view_layer.update()
        w_txt, h_txt = obj.dimensions.x, obj.dimensions.y
        pad = 0.5 * m
        x0, y0 = -half_w + m - pad, half_h - m + pad
        x1, y1 = -half_w + m + w_txt + pad, half_h - m - max(h_txt, size) - pad
        z = -depth * 1.01
        mesh = bpy.data.meshes.new("CaptionBox")
        mesh.from_pydata([(x0, y0, z), (x0, y1, z), (x1, y1, z), (x1, y0, z)], [], [(0, 1, 2, 3)])
        mesh.materials.append(backing)
        box = bpy.data.objects.new("CaptionBox", mesh)
        scene.collection.objects.link(box)
        box.parent = camera
    return obj


def add_sun(direction, strength=3.0, angle_deg=10.0, name="Sun"):
    """Sun shining along `direction` (world space)."""
    light = bpy.data.lights.new(name, "SUN")
    light.energy = strength
    light.angle = math.radians(angle_deg)
    obj = bpy.data.objects.new(name, light)
    obj.rotation_euler = Vector(direction).normalized().to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(obj)
    return obj


def bounding_sphere(points) -> tuple[np.ndarray, float]:
    p = np.asarray(points, dtype=np.float64)
    c = 0.5 * (p.min(0) + p.max(0))
    return c, float(np.linalg.norm(p - c, axis=1).max())


def add_camera(scene, center, radius, view_dir, lens=50.0, margin=1.04, points=None):
    """Camera looking from direction `view_dir` (world +Z up) at `center`.

    Without `points` the distance makes the sphere of `radius` fit the smaller
    field of view; with `points` (N,3) the camera is aimed at the middle of
    their projection and moved as close as the perspective allows (tight
    framing). Either way the framing is the same at every output size.
    """
    cam = bpy.data.cameras.new("Camera")
    cam.lens = lens
    cam.sensor_fit = "AUTO"
    obj = bpy.data.objects.new("Camera", cam)
    scene.collection.objects.link(obj)
    scene.camera = obj
    w, h = scene.render.resolution_x, scene.render.resolution_y
    t_long = 0.5 * cam.sensor_width / lens
    tx, ty = (t_long, t_long * h / w) if w >= h else (t_long * w / h, t_long)
    d = Vector(view_dir).normalized()
    rot = (-d).to_track_quat("-Z", "Y")
    obj.rotation_euler = rot.to_euler()
    c = Vector(center)
    if points is None:
        dist = margin * radius / math.sin(math.atan(min(tx, ty)))
    else:
        right = np.array(rot @ Vector((1.0, 0.0, 0.0)))
        up = np.array(rot @ Vector((0.0, 1.0, 0.0)))
        rel = np.asarray(points, dtype=np.float64) - np.array(c)
        x, y = rel @ right, rel @ up
        c = c + Vector(0.5 * (x.max() + x.min()) * right + 0.5 * (y.max() + y.min()) * up)
        rel = np.asarray(points, dtype=np.float64) - np.array(c)
        x, y, z = rel @ right, rel @ up, rel @ np.array(d)
        dist = float(np.max(np.maximum(z + margin * np.abs(x) / tx, z + margin * np.abs(y) / ty)))
    obj.location = c + float(dist) * d
    return obj


def pixel_size(scene, camera, center) -> float:
    """World-space size of one pixel at the distance of `center` (for line widths)."""
    w, h = scene.render.resolution_x, scene.render.resolution_y
    cam = camera.data
    dist = (camera.location - Vector(center)).length
    half_long = math.atan(0.5 * cam.sensor_width / cam.lens)
    return 2.0 * dist * math.tan(half_long) / max(w, h)


def render(scene, path: Path, transparent: bool = False) -> Path:
    scene.render.film_transparent = transparent
    scene.render.image_settings.color_mode = "RGBA" if transparent else "RGB"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return Path(path)


def load_png(path) -> np.ndarray:
    """PNG -> float array (H, W, 4) in [0, 1], top row first (display-referred values)."""
    img = bpy.data.images.load(str(path), check_existing=False)
    img.colorspace_settings.name = "Non-Color"  # raw byte values, no conversion
    w, h = img.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    return buf.reshape(h, w, 4)[::-1].copy()


def save_png(rgb: np.ndarray, path) -> Path:
    """Save a float (H, W, 3|4) image in [0, 1] (top row first) as an 8-bit RGB PNG."""
    h, w = rgb.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = np.clip(rgb[..., :3], 0.0, 1.0)
    img = bpy.data.images.new("out", w, h, alpha=False)
    img.colorspace_settings.name = "Non-Color"
    img.pixels.foreach_set(rgba[::-1].ravel())
    img.filepath_raw = str(path)
    img.file_format = "PNG"
    scene = bpy.context.scene
    settings = scene.render.image_settings
    settings.color_mode, settings.compression = "RGB", 90
    img.save_render(str(path), scene=scene)
    bpy.data.images.remove(img)
    return Path(path)


def alpha_over(top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """Straight-alpha 'over' of an RGBA layer on an RGB(A) image (same size)."""
    a = top[..., 3:4]
    return top[..., :3] * a + bottom[..., :3] * (1.0 - a)


def side_by_side(images, gap: int = 4, gap_colour=1.0) -> np.ndarray:
    h = images[0].shape[0]
    parts = []
    for i, im in enumerate(images):
        if i:
            parts.append(np.full((h, gap, 3), gap_colour, dtype=np.float32))
        parts.append(im[..., :3])
    return np.concatenate(parts, axis=1)
