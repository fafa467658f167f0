"""The ring of `reachable by`: an outer convex cell less a hole and a gap, from rays (prsc/constraints/reach_ring.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prsc.constraints.reach_ring import contains, ring_from_rays

SECTORS = 36
ANGLES = [-math.pi + 2 * math.pi * j / SECTORS for j in range(SECTORS)]
HEIGHTS = [0.0, 0.05, 0.15]


def _points(radius: float, angle: float, z: float) -> np.ndarray:
    return np.array([[radius * math.cos(angle), radius * math.sin(angle), z]])


def _inside(ring, radius: float, angle: float, z: float = 0.0) -> bool:
    return bool(contains(ring, _points(radius, angle, z))[0])


def test_a_full_ring_keeps_the_annulus_and_nothing_else():
    rays = [[(0.2, 0.7)] * len(HEIGHTS) for _ in ANGLES]
    ring = ring_from_rays(ANGLES, HEIGHTS, rays, 0.006, 0.01)
    assert np.array_equal(ring.hole_a, ring.gap_a)  # no gap: the gap repeats the hole
    for angle in np.linspace(-math.pi, math.pi, 50):
        assert _inside(ring, 0.23, angle) and _inside(ring, 0.68, angle, 0.1)
        assert not _inside(ring, 0.2, angle) and not _inside(ring, 0.695, angle) and not _inside(ring, 0.05, angle)
    assert not _inside(ring, 0.4, 0.0, 0.16) and not _inside(ring, 0.4, 0.0, -0.01)  # the heights measured only
    # What it keeps of the annulus, counted on a grid: above 95 %.
    step = 0.004
    xs = np.arange(-0.72, 0.72, step)
    grid = np.stack(np.meshgrid(xs, xs), axis=-1).reshape(-1, 2)
    radius = np.hypot(grid[:, 0], grid[:, 1])
    annulus = (radius > 0.2) & (radius < 0.7)
    kept = contains(ring, np.hstack([grid, np.full((len(grid), 1), 0.07)]))
    assert not np.any(kept & ~annulus)
    assert np.count_nonzero(kept) / np.count_nonzero(annulus) > 0.95


def test_a_ray_without_reach_makes_a_gap_and_only_there():
    rays = [[(0.2, 0.7)] * len(HEIGHTS) for _ in ANGLES]
    rays[0] = [None] * len(HEIGHTS)  # straight behind, as a base joint of +-170 degrees
    ring = ring_from_rays(ANGLES, HEIGHTS, rays, 0.006, 0.01)
    assert not _inside(ring, 0.5, math.pi) and not _inside(ring, 0.5, math.radians(175))
    assert _inside(ring, 0.5, math.radians(165)) and _inside(ring, 0.5, math.radians(-165)) and _inside(ring, 0.5, 0.0)
    assert _inside(ring, 0.25, math.radians(150))


def test_rays_added_at_the_edge_narrow_the_gap_to_them():
    """A base of +-170 degrees: the rays at +-170 and 180 reach nothing; rays added at
    +-169 (as arm_reach adds them) keep the sectors up to them, and the gap is what is left."""
    rays = {angle: [(0.2, 0.7)] * len(HEIGHTS) for angle in ANGLES}
    for degrees in (-180, -170, 170):
        rays[ANGLES[(degrees + 180) // 10]] = [None] * len(HEIGHTS)
    without = ring_from_rays(ANGLES, HEIGHTS, list(rays.values()), 0.003, 0.005)
    rays |= {math.radians(169): [(0.2, 0.7)] * len(HEIGHTS), math.radians(-169): [(0.2, 0.7)] * len(HEIGHTS)}
    angles = sorted(rays)
    ring = ring_from_rays(angles, HEIGHTS, [rays[a] for a in angles], 0.003, 0.005)
    for degrees in (162, 168.5, -162, -168.5):
        assert _inside(ring, 0.5, math.radians(degrees)) and not _inside(without, 0.5, math.radians(degrees))
    for degrees in (169.5, 175, 180, -175, -169.5):
        assert not _inside(ring, 0.5, math.radians(degrees)), degrees
    assert _inside(ring, 0.6, math.radians(165)) and not _inside(ring, 0.699, math.radians(165))
    assert _inside(ring, 0.21, math.radians(165)) and not _inside(ring, 0.2, math.radians(165))


def test_evenly_spaced_rays_give_the_rows_they_always_did():
    """The sectors' half angles are pi / n for evenly spaced rays, whatever the rounding of
    the angles' differences: the Panda's ring and every cached ring stay the same to the bit."""
    from prsc.constraints.reach_ring import _half_sectors

    assert _half_sectors(ANGLES) == [math.pi / SECTORS] * SECTORS


def test_reach_within_half_a_turn_is_cut_to_its_angles():
    rays = [[(0.2, 0.7)] * len(HEIGHTS) if abs(angle) <= math.radians(60) + 1e-9 else [None] * len(HEIGHTS)
            for angle in ANGLES]
    ring = ring_from_rays(ANGLES, HEIGHTS, rays, 0.006, 0.01)
    assert _inside(ring, 0.5, 0.0) and _inside(ring, 0.5, math.radians(55))
    assert not _inside(ring, 0.5, math.radians(65)) and not _inside(ring, 0.5, math.radians(-90))
    assert not _inside(ring, 0.1, 0.0)


def test_radii_that_change_with_height_are_kept_on_their_safe_side():
    """Inner radii convex in the height (0.1, 0.1, 0.3) and outer radii that dip (0.7, 0.5, 0.7):
    no point closer than the interpolated inner radius or farther than the interpolated outer one."""
    rays = [[(0.1, 0.7), (0.1, 0.5), (0.3, 0.7)] for _ in ANGLES]
    ring = ring_from_rays(ANGLES, HEIGHTS, rays, 0.0, 0.0)
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-0.8, 0.8, 20000), rng.uniform(-0.8, 0.8, 20000), rng.uniform(0, 0.15, 20000)])
    kept = contains(ring, points)
    radius = np.hypot(points[:, 0], points[:, 1])
    inner = np.interp(points[:, 2], HEIGHTS, [0.1, 0.1, 0.3])
    outer = np.interp(points[:, 2], HEIGHTS, [0.7, 0.5, 0.7])
    assert kept.sum() > 1000
    assert not np.any(kept & ((radius < inner - 1e-9) | (radius > outer + 1e-9)))


def test_no_reach_is_an_error():
    with pytest.raises(ValueError, match="reaches no sector"):
        ring_from_rays(ANGLES, HEIGHTS, [[None] * len(HEIGHTS) for _ in ANGLES], 0.006, 0.01)


@pytest.mark.parametrize("args, message", [
    (["--tcp", "nope"], "--tcp 'nope' is no link or site of"),
    (["--grid", "0"], "--grid must be a step > 0 m"),
])
def test_prsc_reach_refuses_a_bad_tool_or_grid(tmp_path, capsys, args, message):
    from prsc.cli import main
    from tests.assets.test_user_arms import MJCF_ARM

    (tmp_path / "arm.xml").write_text(MJCF_ARM)
    assert main(["reach", str(tmp_path / "arm.xml"), *args]) == 2
    assert message in capsys.readouterr().err


class _ReachesBands:
    """A stand-in for arm_reach.TopDownIK: the tool reaches top-down exactly at the radii in `bands`."""

    def __init__(self, bands: list[tuple[float, float]], span: float) -> None:
        self.bands, self._span = bands, span

    def reaches(self, point, seed, restarts: int = 0):
        radius = float(np.hypot(point[0], point[1]))
        return seed, any(lo <= radius <= hi for lo, hi in self.bands)

    def reaches_from_home(self, point) -> bool:
        return self.reaches(point, None)[1]

    def turned(self, angle: float):
        return np.zeros(1)

    def span(self) -> float:
        return self._span


def test_a_ray_keeps_its_longest_run_not_a_sliver_beside_the_base():
    """robosuite's Sawyer reached 0.10 m, then nothing to 0.4 m, then on to 1 m: the first run
    alone made one sector 0.10 m long, and its rows cut the whole cell (4.9 % kept)."""
    from prsc.constraints.arm_reach import _ray

    inner, outer = _ray(_ReachesBands([(0.09, 0.11), (0.38, 1.0)], span=1.1), 0.3, 0.0)
    assert inner == pytest.approx(0.38, abs=0.004) and outer == pytest.approx(1.0, abs=0.004)
    # One run: the same as before, and the scan stops where the rest cannot hold a longer run.
    ik = _ReachesBands([(0.2, 0.7)], span=0.75)
    assert _ray(ik, 0.3, 0.0) == (pytest.approx(0.2, abs=0.004), pytest.approx(0.7, abs=0.004))
