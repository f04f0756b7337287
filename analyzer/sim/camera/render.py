"""The world seen through a lens: perspective from a position and an attitude, by ray casting."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from analyzer.sim.camera.world import (
    DETAIL_CONTRAST,
    DETAIL_M_PER_PX,
    DETAIL_PX,
    HAZE,
    HAZE_M,
    SKY_HORIZON,
    SKY_ZENITH,
    THERMAL_DETAIL_CONTRAST,
    World,
)

SKY_COLD = 0.04  # the sky's temperature on the thermal image
THERMAL_HAZE = 0.35
MAX_RANGE_M = 40_000.0  # beyond this a ray counts as the sky


@dataclass(frozen=True)
class View:
    """Where the lens is (metres east, north and up of home) and where it looks: yaw from
    north (clockwise), pitch (up positive), and the horizontal field of view."""

    east_m: float
    north_m: float
    up_m: float
    yaw_deg: float
    pitch_deg: float
    hfov_deg: float


def focal_px(hfov_deg: float, width: int) -> float:
    """The focal length in pixels of a lens with that horizontal field of view."""
    return (width / 2) / math.tan(math.radians(hfov_deg) / 2)


def hfov_for(zoom: float, hfov_1x: float) -> float:
    """The horizontal field of view at a zoom ratio (the focal length grows with the ratio)."""
    return math.degrees(2 * math.atan(math.tan(math.radians(hfov_1x) / 2) / max(zoom, 1e-6)))


class _Rays:
    """Each pixel's ray, and where it meets the ground (no roll: a stabilised gimbal)."""

    def __init__(self, view: View, width: int, height: int) -> None:
        f = focal_px(view.hfov_deg, width)
        yaw, pitch = math.radians(view.yaw_deg), math.radians(view.pitch_deg)
        forward = np.array(
            [math.cos(pitch) * math.sin(yaw), math.cos(pitch) * math.cos(yaw), math.sin(pitch)]
        )
        right = np.array([math.cos(yaw), -math.sin(yaw), 0.0])
        up = np.cross(right, forward)
        u = ((np.arange(width, dtype=np.float32) - (width - 1) / 2) / f)[None, :]
        v = ((np.arange(height, dtype=np.float32) - (height - 1) / 2) / f)[:, None]
        self.dx = (forward[0] - v * up[0]) + u * right[0]
        self.dy = (forward[1] - v * up[1]) + u * right[1]
        dz = (forward[2] - v * up[2]).astype(np.float32)  # one value per row
        self.dz = dz
        self.focal = f
        altitude = max(view.up_m, 0.1)
        centre_norm = np.sqrt((forward[0] - v * up[0]) ** 2 + (forward[1] - v * up[1]) ** 2 + dz**2)
        self.elevation = np.arcsin(np.clip(dz / centre_norm, -1.0, 1.0))  # per row
        with np.errstate(divide="ignore"):
            t = np.where(dz < 0, altitude / -np.minimum(dz, -1e-9), np.inf)
        self.distance = t * centre_norm  # along the ray through the middle column
        ground = self.distance < MAX_RANGE_M
        rows = np.flatnonzero(ground[:, 0])
        self.ground = slice(int(rows[0]), int(rows[-1]) + 1) if rows.size else slice(0, 0)
        self.t = t.astype(np.float32)
        graze = np.maximum(-dz / centre_norm, 0.05)
        # metres of ground one pixel covers on each row (a whole-row estimate)
        self.footprint = (self.distance / f / graze).astype(np.float32)
        self.view = view


def _level_weights(lod: np.ndarray, levels: int) -> list[np.ndarray]:
    """For each mip level, its weight per row given the wanted level of detail (float)."""
    lod = np.clip(lod, 0.0, levels - 1.0)
    return [
        np.maximum(0.0, 1.0 - np.abs(lod - level)).astype(np.float32) for level in range(levels)
    ]


def _rows(weight: np.ndarray) -> slice:
    found = np.flatnonzero(weight[:, 0] > 1e-4)
    return slice(int(found[0]), int(found[-1]) + 1) if found.size else slice(0, 0)


def _sample(
    image: np.ndarray, east: np.ndarray, north: np.ndarray, m_per_px: float, origin: tuple
) -> np.ndarray:
    """Bilinear samples of a repeating map at ground points (metres from ``origin``)."""
    size_y, size_x = image.shape[:2]
    mapx = _coordinates(east, 1 / m_per_px, (origin[0] / m_per_px) % size_x, size_x)
    mapy = _coordinates(north, -1 / m_per_px, (-origin[1] / m_per_px) % size_y, size_y)
    return cv2.remap(image, mapx, mapy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)


def _coordinates(metres: np.ndarray, scale: float, offset: float, size: int) -> np.ndarray:
    """Map coordinates (float32) folded into the map (remap's own wrapping is slow, and
    its coordinates are 16-bit fixed point)."""
    out = np.multiply(metres, np.float32(scale), dtype=np.float32)
    out += np.float32(offset)
    turns = np.floor(out * np.float32(1 / size))  # np.mod is 40 times slower on float32
    turns *= np.float32(size)
    out -= turns
    return out


def _ground(
    rays: _Rays, levels: tuple[np.ndarray, ...], world: World, contrast: tuple[float, ...]
) -> tuple[np.ndarray, slice]:
    """The map seen on the ground rows, with detail at the scale each row needs."""
    rows = rays.ground
    view = rays.view
    t = rays.t[rows]
    east = rays.dx[rows] * t
    north = rays.dy[rows] * t
    origin = (view.east_m, view.north_m)
    footprint = rays.footprint[rows]
    channels = levels[0].shape[2:] if levels[0].ndim == 3 else ()
    out = np.zeros((east.shape[0], east.shape[1], *channels), np.float32)
    scale = np.float32(1 / 255) if levels[0].dtype == np.uint8 else np.float32(1)
    lod = np.log2(np.maximum(footprint, 1e-6) / world.m_per_px)
    for level, weight in enumerate(_level_weights(lod, len(levels))):
        part = _rows(weight)
        if part.stop <= part.start:
            continue
        m_per_px = world.m_per_px * 2**level
        sampled = _sample(levels[level], east[part], north[part], m_per_px, origin)
        w = (weight[part] if not channels else weight[part][..., None]) * scale
        out[part] += sampled * w
    texture = np.ones(east.shape, np.float32)
    octaves = zip(DETAIL_M_PER_PX, contrast, world.detail, strict=True)
    for octave, (texel, amount, detail) in enumerate(octaves):
        # an octave fades in while its texels grow from half a pixel to a pixel wide
        weight = np.clip(np.log2(texel / np.maximum(footprint, 1e-9)) + 1, 0.0, 1.0) * amount
        part = _rows(weight)
        if part.stop <= part.start:
            continue
        # each octave repeats along its own axes: no grid shared by all of them, where a
        # picture moved by one period would look the same again
        c, s = math.cos(0.5 + 0.7 * octave), math.sin(0.5 + 0.7 * octave)
        u = east[part] * np.float32(c) + north[part] * np.float32(s)
        v = north[part] * np.float32(c) - east[part] * np.float32(s)
        period = texel * DETAIL_PX
        turned = (origin[0] * c + origin[1] * s, origin[1] * c - origin[0] * s)
        shifted = (turned[0] % period, turned[1] % period)
        sampled = _sample(detail, u, v, texel, shifted)
        texture[part] += sampled * weight[part]
    out *= texture if not channels else texture[..., None]
    return out, rows


def render_visible(world: World, view: View, width: int, height: int) -> np.ndarray:
    """The daylight picture (RGB, uint8, height x width x 3)."""
    rays = _Rays(view, width, height)
    image = np.empty((height, width, 3), np.float32)
    elevation = np.clip(rays.elevation / (math.pi / 2), 0.0, 1.0)[..., None]
    sky = (
        np.array(SKY_HORIZON, np.float32) * (1 - elevation)
        + np.array(SKY_ZENITH, np.float32) * elevation
    )
    image[:] = sky
    sky_rows = _sky_rows(rays)
    if sky_rows.stop > sky_rows.start:
        cloud = _clouds(world, rays, sky_rows)[..., None]
        image[sky_rows] = image[sky_rows] * (1 - 0.8 * cloud) + 0.97 * 0.8 * cloud
    ground, rows = _ground(rays, world.colour, world, DETAIL_CONTRAST)
    if rows.stop > rows.start:
        haze = (1.0 - np.exp(-rays.distance[rows] / HAZE_M)).astype(np.float32)[..., None]
        image[rows] = ground * (1 - haze) + np.array(HAZE, np.float32) * haze
    return np.clip(image * 255.0, 0, 255).astype(np.uint8)


def render_thermal(world: World, view: View, width: int, height: int) -> np.ndarray:
    """The temperatures seen (float32, 0 cold .. 1 hot, height x width)."""
    rays = _Rays(view, width, height)
    image = np.full((height, width), SKY_COLD, np.float32)
    ground, rows = _ground(rays, world.temperature, world, THERMAL_DETAIL_CONTRAST)
    if rows.stop > rows.start:
        haze = (1.0 - np.exp(-rays.distance[rows] / HAZE_M)).astype(np.float32)
        image[rows] = ground * (1 - haze) + THERMAL_HAZE * haze
    return image


def _sky_rows(rays: _Rays) -> slice:
    above = np.flatnonzero(rays.distance[:, 0] >= MAX_RANGE_M)
    return slice(int(above[0]), int(above[-1]) + 1) if above.size else slice(0, 0)


def _clouds(world: World, rays: _Rays, rows: slice) -> np.ndarray:
    """Cloud cover where rows look at the sky, by the rays' azimuth and elevation."""
    clouds = world.clouds
    height, width = clouds.shape
    azimuth = np.arctan2(rays.dx[rows], rays.dy[rows])
    mapx = ((azimuth / (2 * math.pi)) % 1.0 * width).astype(np.float32)
    elevation = np.broadcast_to(rays.elevation[rows], mapx.shape)
    mapy = np.clip(elevation / (math.pi / 2) * height * 2.0, 0, height - 1).astype(np.float32)
    return cv2.remap(clouds, mapx, mapy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
