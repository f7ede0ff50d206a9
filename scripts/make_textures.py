#!/usr/bin/env python3
"""Makes the example textures under sequences/textures/ (needs Pillow):
globe.png, a 256x128 equirectangular test map (white north cap, dark south cap, a red arrow
pointing north, meridians every 45 degrees), and wood.png, 64x64 stripes."""
import math
import os
from PIL import Image, ImageDraw

out = os.path.join(os.path.dirname(__file__), "..", "sequences", "textures")
os.makedirs(out, exist_ok=True)

W, H = 256, 128
im = Image.new("RGB", (W, H))
px = im.load()
for y in range(H):
    for x in range(W):
        lat = y / H
        r, g, b = int(40 + 150 * lat), int(90 + 100 * (1 - lat)), 200
        if (x // 16 + y // 16) % 2 == 0:
            r, g, b = r * 3 // 4, g * 3 // 4, b * 3 // 4
        px[x, y] = (r, g, b)
d = ImageDraw.Draw(im)
for x in range(0, W, 32):
    d.line([(x, 0), (x, H - 1)], fill=(240, 240, 240))
d.rectangle([0, 0, W - 1, 10], fill=(250, 250, 250))
d.rectangle([0, H - 11, W - 1, H - 1], fill=(30, 30, 60))
d.polygon([(120, 60), (128, 30), (136, 60)], fill=(220, 40, 40))
im.save(os.path.join(out, "globe.png"), optimize=True)

im = Image.new("RGB", (64, 64))
px = im.load()
for y in range(64):
    for x in range(64):
        t = 0.5 + 0.5 * math.sin(x * 0.6 + 3 * math.sin(y * 0.2))
        px[x, y] = (int(120 + 80 * t), int(70 + 50 * t), int(30 + 20 * t))
im.save(os.path.join(out, "wood.png"), optimize=True)
