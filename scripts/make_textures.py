#!/usr/bin/env python3
"""Makes the example textures under sequences/textures/ (needs Pillow):
globe.png, a 256x128 equirectangular test map (white north cap, dark south cap, a red arrow
pointing north, meridians every 45 degrees), wood.png, 64x64 stripes, and sky.png, a
equirectangular sky, 1024x512 (`render.background: { image: … }`): blue overhead fading to a pale
horizon, soft clouds, a sun a quarter turn right of the image's centre, and below the horizon
a green-brown ground with a line of hills. `make_textures.py sky` writes sky.png alone."""
import math
import os
import sys
from PIL import Image, ImageDraw

out = os.path.join(os.path.dirname(__file__), "..", "sequences", "textures")
os.makedirs(out, exist_ok=True)


def sky_at(azimuth, elevation):
    """The sky's colour (0-1) at an azimuth (0 towards -z, +pi/2 towards +x) and elevation."""
    hills = 0.05 + 0.03 * math.sin(3 * azimuth + 1) + 0.02 * math.sin(7 * azimuth)
    if elevation > hills:
        t = min(1.0, elevation / (math.pi / 2)) ** 0.6
        r, g, b = (0.85 - 0.65 * t, 0.88 - 0.5 * t, 0.95 - 0.2 * t)
        cloud = math.sin(5 * azimuth + 2 * math.sin(9 * elevation)) * math.sin(11 * elevation + azimuth)
        cloud = max(0.0, cloud - 0.35) * 1.4 * (1 - t)
        r, g, b = (c + (0.97 - c) * cloud for c in (r, g, b))
        # The sun, a quarter turn to the right (+x), 25 degrees up.
        d = math.hypot(azimuth - math.pi / 2, elevation - math.radians(25))
        glow = math.exp(-((d / 0.08) ** 2))
        return tuple(min(1.0, c + glow) for c in (r, g, b))
    if elevation > 0:
        return (0.25, 0.33, 0.22)
    t = min(1.0, -elevation / (math.pi / 2))
    return (0.32 - 0.12 * t, 0.3 - 0.1 * t, 0.22 - 0.08 * t)


def sky():
    W, H, S = 1024, 512, 3  # S x S samples a pixel, so the hills' edge is smooth
    im = Image.new("RGB", (W, H))
    px = im.load()
    for y in range(H):
        for x in range(W):
            total = [0.0, 0.0, 0.0]
            for i in range(S):
                for j in range(S):
                    elevation = (0.5 - (y + (i + 0.5) / S) / H) * math.pi
                    azimuth = ((x + (j + 0.5) / S) / W - 0.5) * 2 * math.pi
                    total = [a + b for a, b in zip(total, sky_at(azimuth, elevation))]
            px[x, y] = tuple(int(255 * c / (S * S) + 0.5) for c in total)
    im.save(os.path.join(out, "sky.png"), optimize=True)


if sys.argv[1:] == ["sky"]:
    sky()
    sys.exit(0)

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

sky()
