"""Renders the validation scene of crates/cli/tests/mitsuba.rs with Mitsuba 3.

Usage: python render.py SPEC.json OUT.exr

SPEC (written by the test) holds the camera, the mesh, the floor, the
reflectances and one light, either {"point": [x, y, z], "intensity": I}
(Mitsuba's `point` emitter: radiant intensity I, so E = I cos / r^2) or
{"quad": {"corner": c, "edge_u": u, "edge_v": v}, "radiance": L} (a
`rectangle` with an `area` emitter facing edge_u x edge_v). Mitsuba's
`direct` integrator, scalar_rgb, one sample per pixel at the pixel centre
(stratified sampler without jitter, box filter), so that each pixel is the
same camera ray as prism's 1-spp render; with "spp" > 1 (the area light)
independent samples over each pixel, against prism's stratified ones.
"""

import json
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")


def main():
    spec = json.load(open(sys.argv[1]))
    cam = spec["camera"]
    T = mi.ScalarTransform4f
    spp = spec.get("spp", 1)
    # One sample: the pixel centre (no jitter), prism's 1-spp ray. More:
    # independent samples over the pixel (a stratified sampler without
    # jitter would also put every emitter sample at one point of the light).
    if spp == 1:
        sampler = {"type": "stratified", "sample_count": 1, "jitter": False}
    else:
        sampler = {"type": "independent", "sample_count": spp}
    scene = {
        "type": "scene",
        "integrator": {
            "type": "direct",
            "emitter_samples": spec.get("emitter_samples", 1),
            "bsdf_samples": 0,
        },
        "sensor": {
            "type": "perspective",
            "fov": cam["fov"],
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=[0, 1, 0]),
            "sampler": sampler,
            "film": {
                "type": "hdrfilm",
                "width": cam["width"],
                "height": cam["height"],
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        "mesh": {
            "type": "obj",
            "filename": spec["mesh"],
            "face_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": spec["mesh_albedo"]}},
        },
        "floor": {
            "type": "rectangle",
            # Mitsuba's rectangle is [-1, 1]^2 in z = 0 facing +z: turned to face +y.
            "to_world": T().translate([0, spec["floor_y"], 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(50),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": spec["floor_albedo"]}},
        },
    }
    light = spec["light"]
    if "point" in light:
        scene["light"] = {
            "type": "point",
            "position": light["point"],
            "intensity": {"type": "rgb", "value": [light["intensity"]] * 3},
        }
    else:
        q = light["quad"]
        c = [q["corner"][i] + 0.5 * (q["edge_u"][i] + q["edge_v"][i]) for i in range(3)]
        u = [0.5 * x for x in q["edge_u"]]
        v = [0.5 * x for x in q["edge_v"]]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = sum(x * x for x in n) ** 0.5
        n = [x / length for x in n]
        m = [[u[0], v[0], n[0], c[0]], [u[1], v[1], n[1], c[1]], [u[2], v[2], n[2], c[2]], [0, 0, 0, 1]]
        scene["light"] = {
            "type": "rectangle",
            "to_world": T(m),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [light["radiance"]] * 3}},
        }
    image = mi.render(mi.load_dict(scene))
    mi.util.write_bitmap(sys.argv[2], image)


main()
