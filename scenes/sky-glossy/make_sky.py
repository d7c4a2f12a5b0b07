"""Writes the two environment maps of this scene (run with Mitsuba 3's Python package):

- sky.exr: a smooth sky without a sun: a horizon-to-zenith gradient, a broad glow around the
  sun's direction (Gaussian, 20 degrees), a dark ground. Its luminance's relative variance over
  the sphere is 0.57 (`--cached-environment auto` puts it in radiance records).
- sky-sun.exr: the same with a sun disc (1.5 degrees in radius) holding most of the power
  (relative variance 955: auto leaves it to the light samples).

Latitude-longitude, 256 x 128, Mitsuba's mapping (+y up, the image centre looking along +z).
"""
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
W, H = 256, 128
sun = np.array([0.45, 0.55, 0.70])
sun /= np.linalg.norm(sun)


def image(with_sun):
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    phi, theta = np.meshgrid(2 * np.pi * u, np.pi * v)
    d = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], -1)
    up = d[..., 1]
    t = np.sqrt(np.clip(up, 0, 1))[..., None]
    horizon = np.array([1.25, 1.15, 1.0])
    zenith = np.array([0.35, 0.55, 1.05])
    sky = horizon * (1 - t) + zenith * t
    angle = np.arccos(np.clip(d @ sun, -1, 1))
    sky = sky + np.array([1.6, 1.3, 0.9]) * np.exp(-0.5 * (angle / np.radians(20)) ** 2)[..., None]
    ground = np.array([0.22, 0.19, 0.15])
    # A soft horizon line (no discontinuity a bilinear lookup would blur differently).
    blend = np.clip(up / 0.03 + 0.5, 0, 1)[..., None]
    rgb = ground * (1 - blend) + sky * blend
    if with_sun:
        rgb = rgb + np.where(angle < np.radians(1.5), 4000.0, 0.0)[..., None] * np.array([1.0, 0.92, 0.8])
    return rgb.astype(np.float32)


for name, with_sun in [("sky.exr", False), ("sky-sun.exr", True)]:
    mi.Bitmap(image(with_sun)).write(name)
