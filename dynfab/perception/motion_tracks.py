"""Velocities of what moves in a camera's view, per cluster, from frame to frame.

Each frame's points are split into clusters (:func:`~dynfab.perception.clusters.voxel_clusters`);
a cluster of at least ``min_points`` points is summarised by its centroid and its extent per
world axis, the ``q``-th and ``(1 − q)``-th quantiles ``lo`` and ``hi`` (robust to noise and
stray points). Clusters are matched to the previous frame's tracks by nearest centroid, one to
one, nearest pairs first, within the gate ``max_speed · Δt + h``; an unmatched cluster starts
a track. A track's velocity compares its latest summary with the one ``window`` frames back
(or its oldest, if younger), per axis ``k``:

    v_k = median(Δlo_k, Δhi_k, 0) / Δt                            [m/s],

i.e. when both ends of the extent moved the same way, the smaller displacement, else 0. A
rigid translation moves both ends alike and is measured; a cluster that grows or shrinks on
one side only (occluded by the arm, coming into view, filtered where it nears the robot) is
not mistaken for motion: its far end moves at the crop's speed ``s``, its near quantile by at
most ``q s`` (5 % of it), and that is what it reads; a static cluster reads about 0. The difference over ``window`` frames is
the mean of the per-frame velocities, a moving-average low-pass. A new track reads 0 until
its second frame. Two things that touch (closer than ``h``) are one cluster: a thrown ball
passing by a shelf loses its own velocity while they touch.

Given which points *arrived* (a depth camera's frame: their pixels came nearer since the
previous frame, :attr:`~dynfab.perception.depth_camera.CameraFrame.arrived`), only the
clusters holding arrived points are formed and tracked
(:func:`~dynfab.perception.arrival_clusters.arrival_clusters`: within ``reach`` of them,
not cut by that bound); every other point is static and reads 0. A track faster than
``hold_speed`` is followed on without arrivals (a thing moving along the camera's rays
shows few): the points in its latest extent box, grown by the gate, count as arrived. Without
arrivals given, every cluster of the frame is tracked.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dynfab.perception.arrival_clusters import arrival_clusters, rows_in_box
from dynfab.perception.clusters import voxel_clusters

__all__ = ["SUMMARY_POINTS", "ClusterSummary", "ClusterTracker", "MovingCluster"]

#: A cluster's centroid and extents are computed from at most this many of its points, drawn
#: at random (seeded; a large static surface costs no more than a ball, its quantiles then
#: jitter by about ``√(q(1 − q)/n)`` of its extent: 3 mm on 1 m).
SUMMARY_POINTS = 8192


@dataclass(frozen=True)
class ClusterSummary:
    """A cluster at one frame.

    Attributes:
        time: The frame's time [s].
        centroid: Mean of its points (3,) [m].
        lo: Per axis, its ``q``-quantile (3,) [m].
        hi: Per axis, its ``(1 − q)``-quantile (3,) [m].
    """

    time: float
    centroid: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]


@dataclass(frozen=True)
class MovingCluster:
    """A tracked cluster that moves, as a ball that holds what was seen of it.

    Attributes:
        time: The frame it was seen in [s].
        centre: The centre of its extent box ``(lo + hi) / 2`` (3,) [m].
        radius: Half the box's diagonal ``‖hi − lo‖ / 2`` plus the clustering's voxel edge
            (the quantiles trim its ends) [m]. The box of a ball's visible cap reaches from
            its rim to its front, so this covers the ball when seen along an axis (1.5 times
            its radius plus the edge).
        velocity: Its velocity estimate (3,) [m/s].
    """

    time: float
    centre: NDArray[np.float64]
    radius: float
    velocity: NDArray[np.float64]

    def at(self, t: float) -> NDArray[np.float64]:
        """Its centre moved to time ``t`` [s] at its velocity: ``centre + v (t − time)``."""
        return self.centre + self.velocity * (t - self.time)


class _Track:
    """A cluster followed over frames."""

    def __init__(self, summary: ClusterSummary, window: int) -> None:
        self.history: deque[ClusterSummary] = deque([summary], maxlen=window + 1)

    @property
    def latest(self) -> ClusterSummary:
        return self.history[-1]

    def velocity(self) -> NDArray[np.float64]:
        old, new = self.history[0], self.history[-1]
        if new.time <= old.time:
            return np.zeros(3)
        shifts = np.stack([new.lo - old.lo, new.hi - old.hi, np.zeros(3)])
        return np.median(shifts, axis=0) / (new.time - old.time)


class ClusterTracker:
    """Per-point velocity estimates of successive frames (module docstring).

    Attributes:
        edge: Voxel edge ``h`` of the clustering [m].
        min_points: Smallest cluster tracked; smaller ones read 0.
        max_speed: Fastest motion matched between frames [m/s].
        window: Frames between the summaries a velocity compares.
        quantile: ``q`` of the extents.
        seed: Seed of the samples of large clusters.
        reach: With arrived points, how far from them a moving cluster may extend [m].
        min_seeds: With arrived points, fewest a cluster of them needs to be followed.
        hold_speed: With arrived points, a track faster than this [m/s] is followed without.
        tracks: The live tracks (those matched or started at the latest frame).
    """

    def __init__(self, edge: float = 0.03, min_points: int = 20, max_speed: float = 3.0, window: int = 3,
                 quantile: float = 0.05, seed: int = 0, reach: float = 0.3, min_seeds: int = 5,
                 hold_speed: float = 0.05) -> None:
        if not edge > 0.0 or min_points < 1 or not max_speed > 0.0 or window < 1 or not 0.0 <= quantile < 0.5:
            raise ValueError("ClusterTracker needs edge > 0, min_points >= 1, max_speed > 0, window >= 1 and "
                             f"0 <= quantile < 0.5; got {edge}, {min_points}, {max_speed}, {window}, {quantile}")
        if not reach >= 0.0 or min_seeds < 1 or not hold_speed >= 0.0:
            raise ValueError("ClusterTracker needs reach >= 0, min_seeds >= 1 and hold_speed >= 0; got "
                             f"{reach}, {min_seeds}, {hold_speed}")
        self.edge, self.min_points, self.max_speed = edge, min_points, max_speed
        self.reach, self.min_seeds, self.hold_speed = reach, min_seeds, hold_speed
        self.window, self.quantile = window, quantile
        self.tracks: list[_Track] = []
        self._time: float | None = None
        self._rng = np.random.default_rng(seed)

    def update(self, time: float, points: NDArray[np.float64],
               arrived: NDArray[np.bool_] | None = None) -> NDArray[np.float64]:
        """Track the clusters of one frame's points (N, 3) [m] taken at ``time`` [s] (later than
        the previous frame's); each point's velocity estimate (N, 3) [m/s]. ``arrived`` (N,):
        which points arrived (module docstring); None clusters every point."""
        if self._time is not None and not time > self._time:
            raise ValueError(f"frames must come in time order: {time} after {self._time}")
        if arrived is None:
            rows = None
            labels, count = voxel_clusters(points, self.edge)
        else:
            rows, labels, count = arrival_clusters(points, self._held(time, points, arrived), self.edge, self.reach,
                                                   self.min_seeds)
        small = labels.astype(np.uint16) if count <= np.iinfo(np.uint16).max else labels
        order = np.argsort(small, kind="stable")  # a radix sort for 16-bit labels
        starts = np.searchsorted(labels[order], np.arange(count + 1))
        members = order if rows is None else rows[order]
        clusters = {c: members[starts[c]:starts[c + 1]] for c in range(count)
                    if starts[c + 1] - starts[c] >= self.min_points}
        summaries = {c: self._summary(time, points[cluster_rows]) for c, cluster_rows in clusters.items()}
        tracks = self._match(time, summaries)
        velocities = np.zeros((len(points), 3))
        for c, track in tracks.items():
            velocities[clusters[c]] = track.velocity()
        self.tracks = list(tracks.values())
        self._time = time
        return velocities

    def _held(self, time: float, points: NDArray[np.float64], arrived: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """``arrived``, plus the points in the latest box of each track faster than
        ``hold_speed``, grown by the gate ``max_speed · Δt + h``."""
        held = [track.latest for track in self.tracks if np.linalg.norm(track.velocity()) > self.hold_speed]
        if not held or self._time is None:
            return arrived
        seeds = np.array(arrived, dtype=bool)
        gate = self.max_speed * (time - self._time) + self.edge
        for latest in held:
            seeds[rows_in_box(points, latest.lo - gate, latest.hi + gate)] = True
        return seeds

    def velocity_at(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """The velocity estimate (k, 3) [m/s] of points (k, 3) [m] of the latest frame: that of
        the fastest live track whose ball (:meth:`moving`, at the frame's time) holds the
        point, else 0."""
        velocities = np.zeros((len(points), 3))
        for cluster in reversed(self.moving(0.0)):
            inside = np.linalg.norm(points - cluster.centre, axis=1) <= cluster.radius
            velocities[inside] = cluster.velocity
        return velocities

    def moving(self, min_speed: float) -> list[MovingCluster]:
        """The live tracks faster than ``min_speed`` [m/s], fastest first."""
        found = []
        for track in self.tracks:
            velocity = track.velocity()
            if np.linalg.norm(velocity) > min_speed:
                latest = track.latest
                found.append(MovingCluster(latest.time, (latest.lo + latest.hi) / 2,
                                           float(np.linalg.norm(latest.hi - latest.lo)) / 2 + self.edge, velocity))
        return sorted(found, key=lambda cluster: -float(np.linalg.norm(cluster.velocity)))

    def _summary(self, time: float, points: NDArray[np.float64]) -> ClusterSummary:
        if len(points) > SUMMARY_POINTS:  # a random sample: a stride would alias with the image's rows
            points = points[self._rng.integers(0, len(points), SUMMARY_POINTS)]
        lo, hi = np.quantile(points, [self.quantile, 1.0 - self.quantile], axis=0)
        return ClusterSummary(time, points.mean(axis=0), lo, hi)

    def _match(self, time: float, summaries: dict[int, ClusterSummary]) -> dict[int, _Track]:
        """Each cluster's track: the previous frame's nearest within the gate, or a new one."""
        matched: dict[int, _Track] = {}
        if self.tracks and summaries:
            gate = self.max_speed * (time - self._time) + self.edge
            labels = list(summaries)
            new = np.array([summaries[c].centroid for c in labels])
            old = np.array([track.latest.centroid for track in self.tracks])
            distances = np.linalg.norm(new[:, None, :] - old[None, :, :], axis=2)
            taken: set[int] = set()
            for flat in np.argsort(distances, axis=None):
                i, j = divmod(int(flat), len(self.tracks))
                if distances[i, j] > gate:
                    break
                if labels[i] in matched or j in taken:
                    continue
                track = self.tracks[j]
                track.history.append(summaries[labels[i]])
                matched[labels[i]] = track
                taken.add(j)
        for c, summary in summaries.items():
            if c not in matched:
                matched[c] = _Track(summary, self.window)
        return matched
