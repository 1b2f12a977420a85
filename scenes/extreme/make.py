#!/usr/bin/env python3
"""Writes the stiff and extreme scenes of this folder. Run from the repository root:
   python3 scenes/extreme/make.py
The scaled twins are the lecture scene with every length, ambient and emissivity multiplied
by the same factor: ambient/R and E/r are unchanged, so the image must not change."""
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
LECTURE = os.path.join(HERE, "..", "cho.txt")


def write(name, comment, body):
    with open(os.path.join(HERE, name), "w") as f:
        f.write("# " + comment + "\n" + body.lstrip("\n"))


def scaled_lecture(factor, name):
    scaled_keys = {"worlddim", "viewpoint", "ambient", "location", "emissivity", "center",
                   "radius", "point"}
    out = []
    for line in open(LECTURE):
        stripped = line.strip()
        if stripped.startswith("#"):
            continue
        words = stripped.lstrip("{").split()
        if words and words[0] in scaled_keys:
            key = words[0]
            values = [repr(float(v) * factor) for v in words[1:]]
            indent = line[: len(line) - len(line.lstrip())]
            prefix = "{  " if stripped.startswith("{") else ""
            out.append(f"{indent}{prefix}{key} {' '.join(values)}\n")
        else:
            out.append(line)
    write(name, f"The lecture scene scaled by {factor:g}: lengths, window, ambient and "
          "emissivity alike, so the image must equal the lecture scene's.", "".join(out))


scaled_lecture(1e6, "scaled-1e6.txt")
scaled_lecture(1e-6, "scaled-1e-6.txt")

write("tiny-far.txt", "A sphere of radius 20 seen from 100,000 units away through a narrow "
      "window: the textbook quadratic in float loses every hit.", """
camera far
{  pixeldim 160 120
   worlddim 0.0008 0.0006
   viewpoint 0.0004 0.0003 1
}
material grey { ambient 20000 diffuse 0.6 specular 0.3 }
light eye_side { location 30 40 10 emissivity 150000 }
sphere small { material grey center 0.0004 0.0003 -100000 radius 20 }
""")

write("huge-close.txt", "A sphere of radius 1e6 seen from close by as a floor, with small "
      "spheres resting on it: cancellation in |f|^2 - r^2.", """
camera c { pixeldim 160 120 worlddim 8 6 viewpoint 4 3 5 }
material ground { ambient 2 diffuse 0.6 }
material red { ambient 5 1 1 diffuse 0.8 0.1 0.1 specular 0.2 }
material mirror { ambient 1 diffuse 0.1 specular 0.8 }
light sun { location 10 20 10 emissivity 30 }
sphere planet { material ground center 4 -1000000 -5 radius 1000000 }
sphere ball { material red center 3 1 -5 radius 1 }
sphere glass { material mirror center 6 0.7 -4 radius 0.7 }
""")

write("tangent-grazing.txt", "Tangent and grazing rays: spheres whose silhouettes fall on "
      "pixel rays exactly, and a floor seen edge-on toward the horizon.", """
camera c { pixeldim 161 121 worlddim 8 6 viewpoint 4 3 5 }
material white { ambient 3 diffuse 0.7 specular 0.3 }
material floor { ambient 2 diffuse 0.5 specular 0.1 }
light top { location 4 8 2 emissivity 6 }
# The eye is at y = 3: this plane is seen exactly edge-on.
plane eye_level { material floor normal 0 1 0 point 0 3 0 }
plane ground { material floor normal 0 1 0 point 0 -1 0 }
# Centre at the eye's height and x: rays through pixel columns graze its sides.
sphere s1 { material white center 4 1 -5 radius 2 }
sphere s2 { material white center 1 0.5 -3 radius 0.5 }
sphere s3 { material white center 7 0.5 -3 radius 0.5 }
""")

write("eye-inside.txt", "The eye inside a large sphere (a dome) with a light and spheres "
      "inside: primary rays start inside and hit the far side.", """
camera c { pixeldim 160 120 worlddim 8 6 viewpoint 4 3 5 }
material dome { ambient 4 diffuse 0.5 specular 0.2 }
material ball { ambient 2 2 5 diffuse 0.2 0.3 0.8 specular 0.4 }
light inner { location 4 5 0 emissivity 5 }
sphere sky { material dome center 4 3 0 radius 30 }
sphere b1 { material ball center 2 2 -6 radius 1 }
sphere b2 { material ball center 6 2 -6 radius 1 }
""")

write("light-on-surface.txt", "Lights exactly on surfaces: one on a sphere, one on the floor "
      "plane; r = 0 at those points must not give NaN.", """
camera c { pixeldim 160 120 worlddim 8 6 viewpoint 4 3 5 }
material m { ambient 2 diffuse 0.6 specular 0.3 }
light on_sphere { location 4 3 -4 emissivity 3 }
light on_floor { location 4 -1 -5 emissivity 3 }
sphere s { material m center 4 3 -5 radius 1 }
plane floor { material m normal 0 1 0 point 0 -1 0 }
""")

write("facing-mirrors.txt", "Two parallel mirror planes facing each other with a sphere "
      "between: deep recursion (render with max_depth 64).", """
camera c { pixeldim 160 120 worlddim 8 6 viewpoint 4 3 5 }
material mirror { ambient 0.2 diffuse 0.05 specular 0.95 }
material red { ambient 6 1 1 diffuse 0.8 0.1 0.1 }
light l { location 4 5 -2 emissivity 4 }
plane left { material mirror normal 1 0 0 point 0.5 0 0 }
plane right { material mirror normal -1 0 0 point 7.5 0 0 }
sphere ball { material red center 4 2.5 -6 radius 1 }
""")

write("coincident-touching.txt", "Coincident spheres (same centre and radius), touching "
      "spheres, and a sphere touching the floor.", """
camera c { pixeldim 160 120 worlddim 8 6 viewpoint 4 3 5 }
material a { ambient 5 1 1 diffuse 0.7 0.1 0.1 specular 0.3 }
material b { ambient 1 1 5 diffuse 0.1 0.1 0.7 specular 0.3 }
material floor { ambient 2 diffuse 0.5 specular 0.2 }
light l { location 4 8 2 emissivity 6 }
sphere twin1 { material a center 2 1 -5 radius 1 }
sphere twin2 { material b center 2 1 -5 radius 1 }
sphere touch1 { material a center 5 1 -5 radius 1 }
sphere touch2 { material b center 7 1 -5 radius 1 }
plane floor { material floor normal 0 1 0 point 0 0 0 }
""")

for name, w, h, what in [("one-by-one.txt", 1, 1, "A 1x1 image: the single pixel looks "
                          "through the window's centre."),
                         ("one-by-n.txt", 1, 240, "A 1xN image: one column through the "
                          "window's centre."),
                         ("n-by-one.txt", 320, 1, "An Nx1 image: one row through the "
                          "window's middle.")]:
    write(name, what, f"""
camera c {{ pixeldim {w} {h} worlddim 8 6 viewpoint 4 3 5 }}
material m {{ ambient 3 diffuse 0.6 specular 0.3 }}
light l {{ location 4 8 2 emissivity 6 }}
sphere s {{ material m center 4 3 -5 radius 2 }}
plane floor {{ material m normal 0 1 0 point 0 -1 0 }}
""")

write("wide-window.txt", "A very wide window close to the eye: a field of view near 180 "
      "degrees, rays almost parallel to the screen.", """
camera c { pixeldim 160 120 worlddim 20000 15000 viewpoint 10000 7500 1 }
material m { ambient 3 diffuse 0.6 specular 0.3 }
material floor { ambient 2 diffuse 0.5 }
light l { location 10000 7510 0 emissivity 10 }
sphere s { material m center 10000 7500 -5 radius 2 }
plane floor { material floor normal 0 1 0 point 0 7490 0 }
""")

write("narrow-window.txt", "A near-zero window (1e-9 wide): every ray is nearly the same; "
      "the pixels must still differ smoothly, not in steps or NaN.", """
camera c { pixeldim 160 120 worlddim 1e-9 7.5e-10 viewpoint 5e-10 3.75e-10 5 }
material m { ambient 3 diffuse 0.6 specular 0.3 }
light l { location 1 1 2 emissivity 6 }
sphere s { material m center 0 0 -5 radius 1 }
""")
