"""Pixels -> metres in the loop plane: a homography from the image to a plane frame (X right, Y up).

Two sources:

- a marker: an ArUco marker (OpenCV's aruco module) of known side, printed, hung level in the loop
  plane; its four corners (found at half resolution, refined to sub-pixel at full), give the homography, including the perspective of a
  camera a few degrees off the plane's normal. The plane frame is the marker's: X along its top edge,
  Y up along its side, so X is horizontal when the marker hangs level.
- camera intrinsics and the distance to the loop plane: focal length (px), principal point, the
  distance along the optical axis, and, if known, the camera's yaw / pitch off the plane normal and its
  roll (degrees); the plane frame is horizontal X, vertical Y, origin where the optical axis meets the plane.

Either way the frame's origin is moved to the exit point later (table frame, see table_frame()).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from robowrangler_sim.identify.errors import CalibrationError

MIN_MARKER_SIDE_PX = 24.0


@dataclass(frozen=True)
class PlaneCalibration:
    """A homography from image pixels (u right, v down, pixel centres at integers) to plane metres (X, Y up).

    Attributes:
        image_to_plane: shape (3, 3).
        source: how it was obtained (for the table's ``source`` field).
    """

    image_to_plane: np.ndarray
    source: str

    def to_plane(self, uv: np.ndarray) -> np.ndarray:
        """Pixels (K, 2) -> plane metres (K, 2)."""
        pts = np.asarray(uv, dtype=np.float64).reshape(-1, 1, 2)
        return cv2.perspectiveTransform(pts, self.image_to_plane).reshape(-1, 2)

    def to_image(self, xy_m: np.ndarray) -> np.ndarray:
        """Plane metres (K, 2) -> pixels (K, 2)."""
        pts = np.asarray(xy_m, dtype=np.float64).reshape(-1, 1, 2)
        return cv2.perspectiveTransform(pts, np.linalg.inv(self.image_to_plane)).reshape(-1, 2)

    def metres_per_px(self, uv: tuple[float, float]) -> float:
        """Local scale at a pixel (mean of the two axes), metres per pixel."""
        u, v = uv
        p = self.to_plane(np.array([[u, v], [u + 1.0, v], [u, v + 1.0]]))
        return 0.5 * float(np.linalg.norm(p[1] - p[0]) + np.linalg.norm(p[2] - p[0]))

    @classmethod
    def from_marker(cls, gray: np.ndarray, *, side_m: float, marker_id: int = 0, dictionary: str = "DICT_4X4_50",
                    path=None) -> "PlaneCalibration":
        """Find the ArUco marker ``marker_id`` of ``dictionary`` and map its corners to a square of ``side_m``.

        Raises CalibrationError (naming ``path``) when it is not found, found more than once, or too small.
        """
        if not (math.isfinite(side_m) and side_m > 0):
            raise CalibrationError(path, f"marker side_m: expected > 0, got {side_m!r}")
        if not hasattr(cv2.aruco, dictionary):
            raise CalibrationError(path, f"marker dictionary: expected an OpenCV aruco dictionary such as "
                                         f"DICT_4X4_50, got {dictionary!r}")
        detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)),
                                           cv2.aruco.DetectorParameters())
        # find at half resolution (4 x faster on a 4 MP photo), refine the corners at full resolution
        small = cv2.resize(gray, (gray.shape[1] // 2, gray.shape[0] // 2), interpolation=cv2.INTER_AREA)
        corners, ids, _ = detector.detectMarkers(small)
        found = [] if ids is None else [(c.reshape(4, 2) + 0.5) * 2.0 - 0.5
                                        for c, i in zip(corners, ids.ravel()) if int(i) == marker_id]
        if not found:
            seen = [] if ids is None else sorted(int(i) for i in ids.ravel())
            raise CalibrationError(path, f"calibration marker {dictionary} id {marker_id} not found in the photo"
                                         + (f" (found ids {seen})" if seen else ""))
        if len(found) > 1:
            raise CalibrationError(path, f"calibration marker {dictionary} id {marker_id} found {len(found)} times; "
                                         "expected exactly one")
        quad = found[0].astype(np.float32)
        sides = np.linalg.norm(np.roll(quad, -1, axis=0) - quad, axis=1)
        if sides.min() < MIN_MARKER_SIDE_PX:
            raise CalibrationError(path, f"calibration marker too small: sides {sides.min():.0f} px, expected at least "
                                         f"{MIN_MARKER_SIDE_PX:.0f} px for a usable scale")
        quad = refine_quad_by_edges(gray, quad.astype(np.float64), reach_px=float(np.clip(sides.min() / 30, 2.0, 6.0)))
        h = 0.5 * side_m
        # aruco corner order: top-left, top-right, bottom-right, bottom-left (as printed)
        plane = np.array([[-h, h], [h, h], [h, -h], [-h, -h]])
        homography = cv2.getPerspectiveTransform(quad.astype(np.float32), plane.astype(np.float32))
        return cls(image_to_plane=homography.astype(np.float64),
                   source=f"ArUco marker {dictionary} id {marker_id}, side {side_m:g} m")

    @classmethod
    def from_intrinsics(cls, *, focal_px: float, distance_m: float, principal_px: tuple[float, float],
                        yaw_deg: float = 0.0, pitch_deg: float = 0.0, roll_deg: float = 0.0,
                        path=None) -> "PlaneCalibration":
        """A pinhole camera at ``distance_m`` from the plane along its optical axis.

        Args:
            focal_px: focal length in pixels; principal_px: the principal point (u, v).
            yaw_deg, pitch_deg: the optical axis off the plane normal, about the vertical and the horizontal;
            roll_deg: the camera's rotation about its axis (image horizontal vs world horizontal).
        """
        for name, value in (("focal_px", focal_px), ("distance_m", distance_m)):
            if not (math.isfinite(value) and value > 0):
                raise CalibrationError(path, f"intrinsics {name}: expected > 0, got {value!r}")
        for name, value in (("yaw_deg", yaw_deg), ("pitch_deg", pitch_deg), ("roll_deg", roll_deg)):
            if not (math.isfinite(value) and abs(value) < 60):
                raise CalibrationError(path, f"intrinsics {name}: expected within +-60 deg, got {value!r}")
        yaw, pitch, roll = (math.radians(a) for a in (yaw_deg, pitch_deg, roll_deg))
        # world: plane y = 0, X = world x, Y = world z; the camera looks along `view` at the origin
        view = np.array([math.sin(yaw) * math.cos(pitch), math.cos(yaw) * math.cos(pitch), math.sin(pitch)])
        up = np.array([0.0, 0.0, 1.0])
        up = up * math.cos(roll) + np.cross(view, up) * math.sin(roll) + view * np.dot(view, up) * (1 - math.cos(roll))
        x_cam = np.cross(view, up)
        x_cam /= np.linalg.norm(x_cam)
        y_cam = np.cross(view, x_cam)
        rot = np.vstack([x_cam, y_cam, view])
        position = -distance_m * view
        k = np.array([[focal_px, 0.0, principal_px[0]], [0.0, focal_px, principal_px[1]], [0.0, 0.0, 1.0]])
        # plane point (X, Y) -> world (X, 0, Y) -> camera rot @ (p - position)
        plane_to_cam = np.column_stack([rot[:, 0], rot[:, 2], -rot @ position])
        plane_to_image = k @ plane_to_cam
        return cls(image_to_plane=np.linalg.inv(plane_to_image),
                   source=f"camera intrinsics: f {focal_px:g} px, distance {distance_m:g} m, "
                          f"yaw {yaw_deg:g} pitch {pitch_deg:g} roll {roll_deg:g} deg")


def refine_quad_by_edges(gray: np.ndarray, quad: np.ndarray, *, reach_px: float) -> np.ndarray:
    """Sub-pixel corners of a dark quadrilateral on a light margin: fit a line to each side's edge, intersect.

    Along each side (away from the corners) the edge is where the intensity derivative across the side
    peaks (its centroid); a straight line through those points (least squares) is the side, and
    neighbouring sides meet at the corners. Much steadier than refining the corners themselves, because
    every side contributes dozens of edge points.

    Args:
        quad: shape (4, 2), corners in order around the quadrilateral.
        reach_px: how far across the side to look, pixels.
    Returns: shape (4, 2).
    """
    img = gray.astype(np.float32)
    centre = quad.mean(axis=0)
    offsets = np.arange(-reach_px, reach_px + 1e-9, 0.25)
    lines = []
    for i in range(4):
        a, b = quad[i], quad[(i + 1) % 4]
        along = (b - a) / np.linalg.norm(b - a)
        normal = np.array([-along[1], along[0]])
        if np.dot(normal, 0.5 * (a + b) - centre) < 0:
            normal = -normal  # outward: dark inside, light outside
        n_samples = max(int(np.linalg.norm(b - a) / 2), 8)
        base = a[None, :] + np.linspace(0.15, 0.85, n_samples)[:, None] * (b - a)[None, :]
        pts = base[:, None, :] + offsets[None, :, None] * normal[None, None, :]
        prof = cv2.remap(img, pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE).astype(np.float64)
        grad = np.maximum(np.diff(prof, axis=1), 0.0)
        grad = np.maximum(grad - 0.2 * grad.max(axis=1, keepdims=True), 0.0)
        mid = 0.5 * (offsets[1:] + offsets[:-1])
        total = grad.sum(axis=1)
        ok = total > 1e-6
        shift = (grad[ok] * mid[None, :]).sum(axis=1) / total[ok]
        edge = base[ok] + shift[:, None] * normal[None, :]
        if len(edge) < 4:
            return quad
        vx, vy, x0, y0 = cv2.fitLine(edge.astype(np.float32), cv2.DIST_L2, 0, 0.01, 0.01).ravel()
        lines.append((np.array([x0, y0], float), np.array([vx, vy], float)))
    corners = []
    for i in range(4):
        (p1, d1), (p2, d2) = lines[(i - 1) % 4], lines[i]
        m = np.column_stack([d1, -d2])
        if abs(np.linalg.det(m)) < 1e-9:
            return quad
        t = np.linalg.solve(m, p2 - p1)
        corners.append(p1 + t[0] * d1)
    corners = np.array(corners)
    if np.max(np.linalg.norm(corners - quad, axis=1)) > 3.0:  # refinement ran off: keep the detector's corners
        return quad
    return corners


def calibration_for_photo(spec: dict, gray: np.ndarray, *, path=None) -> PlaneCalibration:
    """The calibration a spec (the manifest's ``calibration`` object) gives for one photo.

    ``{"marker": {"side_m": .., "id": 0, "dictionary": "DICT_4X4_50"}}`` is looked for in every photo;
    ``{"intrinsics": {"focal_px": .., "distance_m": .., "principal_px": [u, v], ...}}`` is the same for all
    (principal point default: the image centre).
    """
    if not isinstance(spec, dict) or not spec:
        raise CalibrationError(path, "calibration missing: expected a marker (side_m) or camera intrinsics "
                                     "(focal_px, distance_m)")
    if "marker" in spec:
        m = spec["marker"]
        try:
            return PlaneCalibration.from_marker(gray, side_m=float(m["side_m"]), marker_id=int(m.get("id", 0)),
                                                dictionary=str(m.get("dictionary", "DICT_4X4_50")), path=path)
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, CalibrationError):
                raise
            raise CalibrationError(path, f"calibration marker: expected {{side_m, id, dictionary}}, got {m!r}") from exc
    if "intrinsics" in spec:
        c = spec["intrinsics"]
        h, w = gray.shape[:2]
        try:
            principal = tuple(float(x) for x in c.get("principal_px", (0.5 * (w - 1), 0.5 * (h - 1))))
            return PlaneCalibration.from_intrinsics(
                focal_px=float(c["focal_px"]), distance_m=float(c["distance_m"]), principal_px=principal,
                yaw_deg=float(c.get("yaw_deg", 0.0)), pitch_deg=float(c.get("pitch_deg", 0.0)),
                roll_deg=float(c.get("roll_deg", 0.0)), path=path)
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, CalibrationError):
                raise
            raise CalibrationError(path, f"calibration intrinsics: expected {{focal_px, distance_m, principal_px?, "
                                         f"yaw_deg?, pitch_deg?, roll_deg?}}, got {c!r}") from exc
    raise CalibrationError(path, f"calibration: expected a 'marker' or 'intrinsics' entry, got keys {sorted(spec)}")
