"""The synthetic operator as a picture: a shaded mannequin ray-cast through a `Camera`.

The geometric projection (`projection.py`) reports where every landmark is. MediaPipe
reports where it guesses a landmark is, and for a limb the body hides (the far arm in a
side view) its guess is far from the truth, differently for every pose. Rendering the
body and running the real pose model on the picture (`pose_model.py`) gives training
data with MediaPipe's own guesses, noise and misses.

The mannequin: capsules for the limbs (the body's own radii), hands (a palm and a
thumb), feet and the torso's sides, ellipsoids for the chest and the head, with a face
(eyes, brows, mouth) and hair so the pose detector finds a person; flat colours for skin,
shirt, trousers, shoes and hair per person (`sample_look`), Lambert shading lit from
above and behind the camera, a ground plane with a checker texture, sky, and pixel
noise. Every ray is cast only inside the
body's box in the image, and each primitive only inside its own box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from proxima.synth.anthropometry import BodyShape
from proxima.synth.camera import Camera

SKIN_TONES = np.array(
    [
        [255, 219, 172],
        [241, 194, 125],
        [224, 172, 105],
        [198, 134, 66],
        [141, 85, 36],
        [92, 56, 30],
    ],
    np.float64,
)
PIXEL_NOISE = 3.0  # grey levels, a clean sensor in daylight


@dataclass(frozen=True)
class Look:
    """One person's colours (RGB 0..255) and the scene's light."""

    skin: tuple[float, float, float]
    shirt: tuple[float, float, float]
    trousers: tuple[float, float, float]
    hair: tuple[float, float, float]
    sky: tuple[float, float, float]
    ground: tuple[float, float, float]
    light: tuple[float, float, float]  # the light's offset from behind the camera (NED)

    def colour(self, part: str) -> np.ndarray:
        shoe = (30.0, 30.0, 30.0)
        table = {"skin": self.skin, "head": self.skin, "shirt": self.shirt,
                 "trousers": self.trousers, "shoe": shoe, "hair": self.hair}  # fmt: skip
        return np.asarray(table[part], np.float64)


def _rgb(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def sample_look(rng: np.random.Generator) -> Look:
    """A random person's colours and a daylight scene: any skin tone, any shirt, darker
    trousers, dark hair; light from above and behind the camera, a little off."""
    skin = SKIN_TONES[rng.integers(len(SKIN_TONES))] * rng.uniform(0.9, 1.05)
    return Look(
        skin=_rgb(np.minimum(skin, 255)),
        shirt=_rgb(rng.uniform(30, 230, 3)),
        trousers=_rgb(rng.uniform(20, 120, 3)),
        hair=_rgb(rng.uniform(10, 90) * np.array([1.0, 0.8, 0.6])),
        sky=_rgb(np.array([170.0, 195.0, 225.0]) * rng.uniform(0.85, 1.1)),
        ground=_rgb(np.array([95.0, 120.0, 80.0]) * rng.uniform(0.7, 1.3)),
        light=_rgb(rng.normal(0.0, 0.2, 3)),
    )


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def hit_capsule(
    origin: np.ndarray, rays: np.ndarray, a: np.ndarray, b: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray]:
    """Distance (N,) along unit `rays` (N, 3) from `origin` to the capsule a-b of
    `radius` (inf where a ray misses it), and the surface normals (N, 3) there."""
    ba, oa = b - a, origin - a
    baba, baoa, oaoa = ba @ ba, oa @ ba, oa @ oa
    bard, rdoa = rays @ ba, rays @ oa
    qa = baba - bard * bard
    qb = baba * rdoa - baoa * bard
    qc = baba * oaoa - baoa * baoa - radius * radius * baba
    h = qb * qb - qa * qc
    side = (h >= 0) & (qa > 1e-12)
    t_side = np.where(side, (-qb - np.sqrt(np.maximum(h, 0))) / np.where(side, qa, 1.0), np.inf)
    y = baoa + np.where(side, t_side, 0.0) * bard
    t = np.where(side & (y > 0) & (y < baba) & (t_side > 0), t_side, np.inf)
    for end in (a, b):  # the round ends
        oc = origin - end
        hb = rays @ oc
        hh = hb * hb - (oc @ oc - radius * radius)
        t_end = np.where(hh > 0, -hb - np.sqrt(np.maximum(hh, 0)), np.inf)
        t = np.minimum(t, np.where(t_end > 0, t_end, np.inf))
    p = origin + rays * np.where(np.isfinite(t), t, 0.0)[:, None]
    s = np.clip(((p - a) @ ba) / max(float(baba), 1e-12), 0, 1)
    return t, _unit(p - (a + s[:, None] * ba))


def hit_ellipsoid(
    origin: np.ndarray, rays: np.ndarray, centre: np.ndarray, axes: np.ndarray, radii: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """As `hit_capsule` for an ellipsoid: `axes` (3, 3) its unit axes as rows, `radii`
    (3,) along them."""
    o = ((origin - centre) @ axes.T) / radii
    d = (rays @ axes.T) / radii
    qa = np.sum(d * d, -1)
    qb = d @ o
    h = qb * qb - qa * (o @ o - 1)
    t = np.where(h > 0, (-qb - np.sqrt(np.maximum(h, 0))) / qa, np.inf)
    t = np.where(t > 0, t, np.inf)
    p = origin + rays * np.where(np.isfinite(t), t, 0.0)[:, None]
    return t, _unit((((p - centre) @ axes.T) / radii**2) @ axes)


@dataclass(frozen=True)
class Capsule:
    a: np.ndarray
    b: np.ndarray
    radius: float
    part: str

    def hit(self, origin: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return hit_capsule(origin, rays, self.a, self.b, self.radius)

    def extent(self) -> tuple[np.ndarray, float]:
        """Points and a radius that bound it."""
        return np.stack([self.a, self.b]), self.radius


@dataclass(frozen=True)
class Ellipsoid:
    centre: np.ndarray
    axes: np.ndarray
    radii: np.ndarray
    part: str

    def hit(self, origin: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return hit_ellipsoid(origin, rays, self.centre, self.axes, self.radii)

    def extent(self) -> tuple[np.ndarray, float]:
        return self.centre[None], float(np.max(self.radii))


Primitive = Capsule | Ellipsoid


def _frame(forward: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Rows forward, left, up: orthonormal, `left` kept, `forward` made square to it."""
    left = _unit(left)
    forward = _unit(forward - (forward @ left) * left)
    return np.stack([forward, left, np.cross(forward, left)])


def mannequin(lm: np.ndarray, body: BodyShape) -> list[Primitive]:
    """The primitives of one pose, world landmarks `lm` (33, 3)."""
    prims: list[Primitive] = []
    for s, e, w in ((11, 13, 15), (12, 14, 16)):
        prims.append(Capsule(lm[s], lm[e], body.upper_arm_radius, "shirt"))
        prims.append(Capsule(lm[e], lm[w], body.forearm_radius, "skin"))
    for w, pinky, index, thumb in ((15, 17, 19, 21), (16, 18, 20, 22)):
        knuckles = (lm[pinky] + lm[index]) / 2
        prims.append(Capsule(lm[w], knuckles + 0.3 * (knuckles - lm[w]), 0.028, "skin"))
        prims.append(Capsule(lm[w], lm[thumb] + 0.4 * (lm[thumb] - lm[w]), 0.012, "skin"))
    for hip, knee, ankle, heel, toe in ((23, 25, 27, 29, 31), (24, 26, 28, 30, 32)):
        prims.append(Capsule(lm[hip], lm[knee], body.thigh_radius, "trousers"))
        prims.append(Capsule(lm[knee], lm[ankle], body.shank_radius, "trousers"))
        prims.append(Capsule(lm[heel], lm[toe], 0.035, "shoe"))
    # The torso: an ellipsoid chest, capsules along its sides, shoulders and hips.
    shoulders, hips = (lm[11] + lm[12]) / 2, (lm[23] + lm[24]) / 2
    up = _unit(shoulders - hips)
    across = lm[11] - lm[12]
    left = _unit(across - (across @ up) * up)
    axes = np.stack([np.cross(left, up), left, up])
    half_h = float(np.linalg.norm(shoulders - hips)) / 2 + 0.05
    radii = np.array([body.torso_depth / 2, body.shoulder_width / 2 - 0.02, half_h])
    prims.append(Ellipsoid((shoulders + hips) / 2, axes, radii, "shirt"))
    for sign in (1.0, -1.0):
        top = shoulders + sign * left * (body.shoulder_width / 2 - 0.06) - up * 0.04
        bottom = hips + sign * left * (body.hip_width / 2 - 0.03) + up * 0.04
        prims.append(Capsule(top, bottom, 0.085, "shirt"))
    prims.append(Capsule(lm[11] - up * 0.03, lm[12] - up * 0.03, 0.07, "shirt"))
    prims.append(Capsule(lm[23], lm[24], 0.1, "trousers"))
    # Neck and head; the head's frame from the ears and the nose.
    ears = (lm[7] + lm[8]) / 2
    head = _frame(lm[0] - ears, lm[7] - lm[8])
    centre = ears + head[2] * 0.02 * body.stature - head[0] * 0.005
    prims.append(Capsule(shoulders, centre - head[2] * 0.05, 0.05, "skin"))
    head_radii = np.array([0.1, body.head_width / 2 + 0.005, 0.125])
    prims.append(Ellipsoid(centre, head, head_radii, "head"))
    return prims


def _face(points: np.ndarray, lm: np.ndarray, look: Look) -> np.ndarray:
    """Colours (N, 3) of head surface `points`: hair at the back and top, eyes with their
    whites, brows and a mouth at the face landmarks, skin elsewhere."""
    ears = (lm[7] + lm[8]) / 2
    head = _frame(lm[0] - ears, lm[7] - lm[8])
    rel = points - ears
    col = np.tile(look.colour("skin"), (len(points), 1))
    col[(rel @ head[0] < 0.02) | (rel @ head[2] > 0.05)] = look.colour("hair")
    for eye in (2, 5):
        dist = np.linalg.norm(points - lm[eye], axis=-1)
        col[dist < 0.02] = (235.0, 235.0, 235.0)
        col[dist < 0.014] = (40.0, 30.0, 30.0)
        brow = np.linalg.norm(points - (lm[eye] + head[2] * 0.022), axis=-1)
        col[brow < 0.011] = look.colour("hair")
    along = _unit(lm[10] - lm[9])
    s = np.clip((points - lm[9]) @ along, 0, float(np.linalg.norm(lm[10] - lm[9])))
    col[np.linalg.norm(points - (lm[9] + s[:, None] * along), axis=-1) < 0.008] = (
        150.0,
        60.0,
        60.0,
    )
    return col


class Renderer:
    """Pictures of one person before one camera at `width` x `height` pixels (the
    camera's field of view; its own resolution only sets the aspect). The background
    and the rays are computed once: the camera does not move within a clip."""

    def __init__(
        self, camera: Camera, look: Look, ground_down: float, width: int = 640, height: int = 360
    ) -> None:
        if width < 16 or height < 16:
            raise ValueError(f"render size must be at least 16x16, got {width}x{height}")
        self.look, self.width, self.height = look, width, height
        self.focal = camera.focal_px * width / camera.width
        self.rotation = camera.world_to_camera()
        self.origin = np.asarray(camera.position, np.float64)
        u = (np.arange(width) + 0.5 - width / 2) / self.focal
        v = (np.arange(height) + 0.5 - height / 2) / self.focal
        uu, vv = np.meshgrid(u, v)
        optical = np.stack([uu, vv, np.ones_like(uu)], -1).reshape(-1, 3)
        self.rays = _unit(optical @ self.rotation)  # world directions, row by row
        sky = np.asarray(look.sky)
        self.background = np.tile(sky, (len(self.rays), 1))
        down = self.rays[:, 2]
        t = (ground_down - self.origin[2]) / np.where(down > 1e-6, down, 1.0)
        ground = (down > 1e-6) & (t > 0)
        p = self.origin + self.rays[ground] * t[ground, None]
        checker = (np.floor(p[:, 0] * 2) + np.floor(p[:, 1] * 2)) % 2
        self.background[ground] = np.asarray(look.ground) * (0.925 + 0.075 * checker)[:, None]
        # Light from behind the camera and above (NED: up is -z), offset per scene.
        self.light = _unit(-self.rotation[2] + np.array([0.0, 0.0, -0.6]) + look.light)

    def _box(self, points: np.ndarray, radius: float) -> tuple[int, int, int, int] | None:
        """The pixel box (x0, y0, x1, y1) that holds `points` (N, 3) grown by `radius`
        metres, or None when a point is behind the camera (then: the whole image)."""
        c = (points - self.origin) @ self.rotation.T
        if np.any(c[:, 2] < 0.05):
            return None
        px = c[:, :2] / c[:, 2:3] * self.focal + [self.width / 2, self.height / 2]
        grow = radius * self.focal / float(c[:, 2].min()) + 1
        x0, y0 = np.floor(px.min(0) - grow).astype(int)
        x1, y1 = np.ceil(px.max(0) + grow).astype(int)
        return max(x0, 0), max(y0, 0), min(x1, self.width), min(y1, self.height)

    def frame(self, lm: np.ndarray, body: BodyShape, rng: np.random.Generator) -> np.ndarray:
        """The picture (height, width, 3) uint8 RGB of world landmarks `lm` (33, 3)."""
        img = self.background.copy()
        box = self._box(lm, 0.2) or (0, 0, self.width, self.height)
        x0, y0, x1, y1 = box
        if x1 > x0 and y1 > y0:
            bw = x1 - x0
            idx = (np.arange(y0, y1)[:, None] * self.width + np.arange(x0, x1)[None, :]).ravel()
            rays = self.rays[idx]
            best = np.full(len(idx), np.inf)
            normal = np.zeros((len(idx), 3))
            col = np.zeros((len(idx), 3))
            is_head = np.zeros(len(idx), bool)
            for prim in mannequin(lm, body):
                own = self._box(*prim.extent())
                if own is None:
                    sub = np.arange(len(idx))
                else:
                    sx0, sy0 = max(own[0], x0) - x0, max(own[1], y0) - y0
                    sx1, sy1 = min(own[2], x1) - x0, min(own[3], y1) - y0
                    if sx1 <= sx0 or sy1 <= sy0:
                        continue
                    sub = (np.arange(sy0, sy1)[:, None] * bw + np.arange(sx0, sx1)[None, :]).ravel()
                t, n = prim.hit(self.origin, rays[sub])
                closer = t < best[sub]
                won = sub[closer]
                best[won], normal[won] = t[closer], n[closer]
                col[won] = self.look.colour(prim.part)
                is_head[won] = prim.part == "head"
            seen = np.isfinite(best)
            points = self.origin + rays * np.where(seen, best, 0.0)[:, None]
            face = seen & is_head
            col[face] = _face(points[face], lm, self.look)
            shade = 0.35 + 0.65 * np.clip(normal @ self.light, 0, 1)
            sub_img = img[idx]
            sub_img[seen] = col[seen] * shade[seen, None]
            img[idx] = sub_img
        img = img.reshape(self.height, self.width, 3) + rng.normal(
            0, PIXEL_NOISE, (self.height, self.width, 3)
        )
        return np.clip(img, 0, 255).astype(np.uint8)
