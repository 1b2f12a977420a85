#!/usr/bin/env python3
"""Makes the worked example's student images: each student is rayfarm with one of the usual
mistakes made (rounding where the course truncates, rows written bottom first, red and blue
swapped, the lecture's equation, no shadow test, no path cap, no reflections).

    scenes/assignments/lab1/make-students.py build/client/rayfarm
"""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
RAYFARM = sys.argv[1] if len(sys.argv) > 1 else "rayfarm"
SCENES = ["spheres", "shadows", "mirror", "glint"]

# student -> scene -> (render options, post-processing) ; a scene left out is not handed in
STUDENTS = {
    "ada": {s: ([], None) for s in SCENES},
    "ben": {s: (["--rounding", "nearest"], None) for s in SCENES},
    "cam": {"spheres": ([], "flip"), "shadows": ([], "flip"), "mirror": ([], "bgr")},
    "dee": {s: (["--profile", "lecture"], None) for s in SCENES},
    "eli": {"spheres": ([], None), "shadows": (["--shadows", "0"], None),
            "mirror": (["--max-dist", "unlimited"], None), "glint": ([], None)},
    "fay": {"spheres": ([], None), "shadows": ([], None),
            "mirror": (["--max-depth", "0"], None), "glint": ([], "wide")},
}


def read_ppm(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)  # rayfarm writes "P6\nW H\n255\n"
    w, h = map(int, parts[1].split())
    return w, h, bytearray(parts[3])


def write_ppm(path, w, h, rgb):
    with open(path, "wb") as f:
        f.write(b"P6\n%d %d\n255\n" % (w, h) + bytes(rgb))


def post(kind, w, h, rgb):
    if kind == "flip":  # rows written from the world's y = 0 up: the picture upside down
        row = 3 * w
        return b"".join(rgb[(h - 1 - y) * row:(h - y) * row] for y in range(h))
    if kind == "bgr":  # each pixel written blue, green, red
        out = bytearray(rgb)
        out[0::3], out[2::3] = rgb[2::3], rgb[0::3]
        return out
    return rgb


def main():
    with tempfile.TemporaryDirectory() as tmp:
        for student, work in STUDENTS.items():
            folder = os.path.join(HERE, "students", student)
            os.makedirs(folder, exist_ok=True)
            for scene, (options, kind) in work.items():
                src = os.path.join(HERE, "scenes", scene + ".txt")
                if kind == "wide":  # the glint's exponent read as 3 instead of 30
                    text = open(src).read().replace("shininess 30", "shininess 3")
                    src = os.path.join(tmp, scene + ".txt")
                    open(src, "w").write(text)
                ppm = os.path.join(tmp, "out.ppm")
                profile = [] if "--profile" in options else ["--profile", "cpsc102"]
                subprocess.run([RAYFARM, "render", src, *profile, *options,
                                "--format", "ppm", "-o", ppm, "-q"], check=True)
                w, h, rgb = read_ppm(ppm)
                out = os.path.join(tmp, "post.ppm")
                write_ppm(out, w, h, post(kind, w, h, rgb))
                # Handed in as PNG to keep the repository small; the grader reads both.
                write_png(out, os.path.join(folder, scene + ".png"))


def write_png(ppm, png):
    import struct
    import zlib
    w, h, rgb = read_ppm(ppm)
    raw = b"".join(b"\x00" + bytes(rgb[y * 3 * w:(y + 1) * 3 * w]) for y in range(h))

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", zlib.crc32(tag + body))

    with open(png, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


if __name__ == "__main__":
    main()
