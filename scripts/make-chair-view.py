#!/usr/bin/env python3
"""Writes tests/data/chair-behind.glb: the shipped chair-on-floor scene
(assets/scenes/chair-on-floor, its licence and attribution there) packed into one .glb with a
glTF camera added, so that the quality cases of issue #51 keep their view whatever the
framing (scene::framing) chooses for the shipped scene.

The view: the three-quarter view the framing chose for a 1:1 image before it preferred the
front (commit b37fe10): from behind the chair (azimuth 169°, 25° up), looking towards the sun.
Run from the repository root: python3 scripts/make-chair-view.py
"""
import json, math, struct, os

SRC = "assets/scenes/chair-on-floor/MixedLightingExample.gltf"
OUT = "tests/data/chair-behind.glb"
EYE = [0.18849972, 0.781273, -1.050112]
YAW, PITCH = 2.9452431, -0.43633235  # GI Lab's Camera: yaw about +Y (0 looks to -Z), pitch up

def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw*bx + ax*bw + ay*bz - az*by, aw*by - ax*bz + ay*bw + az*bx,
            aw*bz + ax*by - ay*bx + az*bw, aw*bw - ax*bx - ay*by - az*bz]

def main():
    g = json.load(open(SRC))
    base = os.path.dirname(SRC)
    blob = bytearray()
    def add(data):
        while len(blob) % 4:
            blob.append(0)
        off = len(blob)
        blob.extend(data)
        return off
    # The one external buffer becomes the GLB's binary chunk; images become buffer views.
    assert len(g["buffers"]) == 1
    bin_data = open(os.path.join(base, g["buffers"][0]["uri"]), "rb").read()
    add(bin_data)
    for img in g.get("images", []):
        data = open(os.path.join(base, img.pop("uri")), "rb").read()
        off = add(data)
        g["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(data)})
        img["bufferView"] = len(g["bufferViews"]) - 1
        img.setdefault("mimeType", "image/jpeg")
    while len(blob) % 4:
        blob.append(0)
    g["buffers"] = [{"byteLength": len(blob)}]
    qy = [0.0, math.sin(YAW / 2), 0.0, math.cos(YAW / 2)]
    qx = [math.sin(PITCH / 2), 0.0, 0.0, math.cos(PITCH / 2)]
    g.setdefault("cameras", []).append({"name": "behind, towards the sun (issue #51)", "type": "perspective",
        "perspective": {"yfov": 0.8, "znear": 0.011, "zfar": 8.4, "aspectRatio": 1.0}})
    g["nodes"].append({"name": "issue-51 camera", "camera": len(g["cameras"]) - 1,
                       "translation": EYE, "rotation": quat_mul(qy, qx)})
    g["scenes"][g.get("scene", 0)]["nodes"].append(len(g["nodes"]) - 1)
    g["asset"]["generator"] = "GI Lab scripts/make-chair-view.py from " + g["asset"].get("generator", "?")
    js = json.dumps(g, separators=(",", ":")).encode()
    js += b" " * ((4 - len(js) % 4) % 4)
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob))
    out += struct.pack("<II", len(js), 0x4E4F534A) + js
    out += struct.pack("<II", len(blob), 0x004E4942) + bytes(blob)
    open(OUT, "wb").write(out)
    print(f"wrote {OUT}: {len(out)} bytes")

main()
