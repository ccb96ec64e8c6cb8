"""Cycles materials: shaded surface, emissive wire, and the zebra (reflection-line) shader."""
from __future__ import annotations

import bpy


def _new(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    for n in list(nodes):
        nodes.remove(n)
    out = nodes.new("ShaderNodeOutputMaterial")
    return mat, nodes, mat.node_tree.links, out


def surface(colour=(0.42, 0.58, 0.80), roughness=0.35, name="Surface"):
    mat, nodes, links, out = _new(name)
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat


def emission(colour=(0.03, 0.03, 0.035), strength=1.0, name="Wire"):
    """Flat colour that ignores lighting (wires, captions)."""
    mat, nodes, links, out = _new(name)
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*colour, 1.0)
    em.inputs["Strength"].default_value = strength
    links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def zebra(stripes: float = 9.0, axis=(0.0, 0.25, 1.0), name="Zebra"):
    """Reflection lines: black/white by the elevation of the reflected view ray.

    The shading normal n gives the reflection vector r = d - 2 (d.n) n
    (Texture Coordinate 'Reflection', world space); the colour is white where
    sin(stripes * asin(r . a)) > 0 for the unit `axis` a, i.e. the surface
    mirrors an environment of `stripes` black and `stripes` white bands of
    equal angle between the poles -a and a. Emission only, so lights and
    sampling noise do not matter: a jump of the normal (a crease, a C^0 kink)
    shifts the stripes abruptly; a jump of curvature (C^1, not C^2) puts corners in them.
    """
    mat, nodes, links, out = _new(name)
    tc = nodes.new("ShaderNodeTexCoord")
    norm = nodes.new("ShaderNodeVectorMath")
    norm.operation = "NORMALIZE"
    links.new(tc.outputs["Reflection"], norm.inputs[0])
    dot = nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    length = sum(c * c for c in axis) ** 0.5
    dot.inputs[1].default_value = tuple(c / length for c in axis)
    links.new(norm.outputs["Vector"], dot.inputs[0])
    asin = nodes.new("ShaderNodeMath")
    asin.operation = "ARCSINE"
    asin.use_clamp = False
    links.new(dot.outputs["Value"], asin.inputs[0])
    scale = nodes.new("ShaderNodeMath")
    scale.operation = "MULTIPLY"
    scale.inputs[1].default_value = stripes
    links.new(asin.outputs["Value"], scale.inputs[0])
    sine = nodes.new("ShaderNodeMath")
    sine.operation = "SINE"
    links.new(scale.outputs["Value"], sine.inputs[0])
    sharp = nodes.new("ShaderNodeMath")
    sharp.operation = "GREATER_THAN"
    sharp.inputs[1].default_value = 0.0
    links.new(sine.outputs["Value"], sharp.inputs[0])
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Strength"].default_value = 1.0
    links.new(sharp.outputs["Value"], em.inputs["Color"])
    links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat
