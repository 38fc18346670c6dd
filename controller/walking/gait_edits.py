"""The edits of a walking plan while it is walked (the emergency step's): footsteps moved, the reference ZMP
overwritten, and both computed ahead as a GaitPatch that is applied later if the plan has not changed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.types import read_only
from controller.interpolation.hoff_arbib import min_jerk
from controller.walking.footsteps import Footstep
from controller.walking.gait_sampling import BOTH, LEFT, RIGHT, GaitParams, Segment, q_of, rpy_matrices


@dataclass(frozen=True, slots=True)
class GaitPatch:
    """A change of the plan computed ahead (GaitGenerator.prepare_set_zmp / prepare_move_swing), nothing changed
    yet; `GaitGenerator.apply` puts it in while the plan is still the one it was computed from."""

    source: tuple  # (sample arrays, next tick, plan version, params) it was computed from, compared by identity
    arrays: dict  # the sample arrays after the change
    #: a moved landing: (segment index, the footstep moved, its segment's end pose (2, 6), a copy of it)
    landing: tuple | None = None


class GaitEdits:
    """GaitGenerator's edits of the plan being walked. A base of GaitGenerator, it works on the generator's sample
    arrays, segments and footsteps, and resamples through it."""

    # what GaitGenerator holds (see its __init__)
    params: GaitParams
    _arrays: dict[str, np.ndarray] | None
    _segments: list[Segment]
    _footsteps: list[Footstep]
    _tick: int
    _origin: int
    _plan_version: int
    _plan_params: GaitParams | None
    _walking: bool
    _stopping_from_rest: bool
    _zmp_offsets: np.ndarray

    def _current_segment(self) -> Segment:
        raise NotImplementedError

    def _resample_from(self, seg_index: int, keep_first: bool = False) -> None:
        raise NotImplementedError

    def move_footsteps(self, xy_by_index: dict[int, tuple[float, float]], landed: bool = False,
                       zmp_world: np.ndarray | None = None) -> None:
        """Move footsteps {index: (x, y) [m]} (world; heights and orientations kept) while the plan is walked: the
        emergency step re-plans its landings from the measured capture point.

        A footstep not stepped yet is replaced. The footstep being stepped on: the rest of its swing bends toward
        the new landing by a min-jerk blend from the pose planned for the next tick (no jump); `landed`: its foot
        has touched the ground there already (earlier than planned), so it stays there and the rest of the step is
        double support. The reference ZMP of the rest of that step is recomputed from the new foot poses (flat
        soles, no toe-heel offsets); the later segments are resampled once.

        `zmp_world`: the reference ZMP of the next ticks, as set_zmp takes it, set with the move (the emergency
        step's, planned from the capture point); the feet's is then not computed where it replaces it."""
        if not self._walking or self._stopping_from_rest:
            raise InvalidState("move_footsteps needs a footstep plan being walked")
        seg_i = self._segments.index(self._current_segment())
        seg = self._segments[seg_i]
        for index in xy_by_index:
            if not seg.index <= index < len(self._footsteps) or (index == seg.index and seg.kind != "step"):
                raise InvalidCommand(f"move_footsteps({index}): only the footstep being stepped on ({seg.index}, "
                                     f"{seg.kind}) or a later one (< {len(self._footsteps)}) may move")
        if landed and seg.index not in xy_by_index:
            raise InvalidState(f"move_footsteps(landed=True) must move the footstep being stepped on ({seg.index})")
        if zmp_world is not None and not landed:
            patch = self._swing_patch(seg_i, xy_by_index, zmp_world)
            if patch is not None:
                self.apply(patch)
                return
        for index, (x_m, y_m) in xy_by_index.items():
            fs = self._footsteps[index]
            if index == seg.index:
                self._bend_swing(seg, fs, float(x_m), float(y_m), landed)
            self._footsteps[index] = fs.replaced(x=float(x_m), y=float(y_m))
        self._plan_version += 1
        self._resample_from(seg_i, keep_first=True)
        if zmp_world is not None:
            self.set_zmp(zmp_world)

    def prepare_move_swing(self, xy_by_index: dict[int, tuple[float, float]],
                           zmp_world: np.ndarray) -> GaitPatch | None:
        """move_footsteps(xy_by_index, zmp_world=zmp_world) computed ahead, the plan unchanged: its patch when it
        takes the swing-only path (_swing_patch), else None (the call itself then does it, or says what is wrong)."""
        if not self._walking or self._stopping_from_rest:
            return None
        seg_i = self._segments.index(self._current_segment())
        seg = self._segments[seg_i]
        if any(not seg.index <= i < len(self._footsteps) or (i == seg.index and seg.kind != "step")
               for i in xy_by_index):
            return None
        return self._swing_patch(seg_i, xy_by_index, zmp_world)

    def _swing_patch(self, seg_i: int, xy_by_index: dict[int, tuple[float, float]],
                     zmp_world: np.ndarray) -> GaitPatch | None:
        """move_footsteps of the footstep in the air when only the final double support follows it and the ZMP
        given replaces all of the feet's: the swing bends and the swing foot's position in the final double support
        moves, nothing else changes (what resampling gives, without it: the emergency step moves its landing
        every tick). None (nothing to patch this way) in any other case."""
        seg = self._segments[seg_i]
        rest = self._segments[seg_i + 1:]
        j0 = self._tick - self._origin
        if (seg.kind != "step" or list(xy_by_index) != [seg.index] or len(rest) != 1 or rest[0].kind != "end"
                or len(zmp_world) < len(self._arrays["zmp"]) - j0):
            return None
        end = rest[0]
        fs = self._footsteps[seg.index]
        x_m, y_m = (float(v) for v in xy_by_index[seg.index])
        sw = LEFT if fs.leg == "lleg" else RIGHT
        a = self._arrays
        base = seg.start_tick - self._origin
        j1 = base + seg.n_ticks
        p, zmp = a["p"].copy(), a["zmp"].copy()
        w = self._swing_blend(seg, j0)
        p[sw, j0:j1, 0] += w * (x_m - fs.x)
        p[sw, j0:j1, 1] += w * (y_m - fs.y)
        e0 = end.start_tick - self._origin
        p[sw, e0:e0 + end.n_ticks, :2] = (x_m, y_m)  # the final double support: the feet where the step ends
        zmp[j0:] = np.asarray(zmp_world, dtype=float)[:len(zmp) - j0]
        q_end = seg.q_end.copy()
        q_end[sw, :2] = (x_m, y_m)
        return GaitPatch(self._source(), {**a, "p": read_only(p), "zmp": read_only(zmp)},
                         (seg_i, fs.replaced(x=x_m, y=y_m), q_end, q_end.copy()))

    def prepare_set_zmp(self, zmp_world: np.ndarray) -> GaitPatch:
        """set_zmp(zmp_world) computed ahead, the plan unchanged (see there)."""
        if not self._walking:
            raise InvalidState("set_zmp needs a walk in progress")
        zmp = self._arrays["zmp"].copy()
        j0 = self._tick - self._origin
        m = min(len(zmp_world), len(zmp) - j0)
        zmp[j0:j0 + m] = np.asarray(zmp_world, dtype=float)[:m]
        return GaitPatch(self._source(), {**self._arrays, "zmp": read_only(zmp)})

    def _source(self) -> tuple:
        return (self._arrays, self._tick, self._plan_version, self.params, self._plan_params, self._walking,
                self._stopping_from_rest)

    def apply(self, patch: GaitPatch) -> bool:
        """Put in a patch computed ahead; False (nothing done) when the plan is no longer the one it was computed
        from (a tick, a new plan or re-plan, a ZMP set, new parameters, the walk ended), the caller then redoes it."""
        arrays, tick, version, params, plan_params, walking, stopping = patch.source
        if not (self._arrays is arrays and self._tick == tick and self._plan_version == version
                and self.params is params and self._plan_params is plan_params and self._walking == walking
                and self._stopping_from_rest == stopping):
            return False
        self._arrays = patch.arrays
        if patch.landing is not None:
            seg_i, fs, q_end, q_end_copy = patch.landing
            seg, end = self._segments[seg_i], self._segments[seg_i + 1]
            seg.q_end = q_end
            end.q_start, end.q_end = q_end, q_end_copy
            self._footsteps[seg.index] = fs
            self._plan_version += 1
        return True

    def _swing_blend(self, seg: Segment, j0: int) -> np.ndarray:
        """The min-jerk blend [-] toward a moved landing of the segment's samples from j0 (array row) on: local rows
        0 .. n_land - 1 swing (t < ta), the blend reaching 1 on the last of them."""
        gp = seg.params or self.params
        base = seg.start_tick - self._origin
        n_land = int(np.ceil((1.0 - gp.double_support_ratio_after) * seg.n_ticks - 1e-9)) - 1
        i = np.arange(j0, base + seg.n_ticks) - base
        i0 = j0 - base
        return np.where(i >= n_land - 1, 1.0, min_jerk((i - i0 + 1) / max(n_land - i0, 1)))

    def _bend_swing(self, seg: Segment, fs: Footstep, x_m: float, y_m: float, landed: bool) -> None:
        """move_footsteps' patch of the rest of the segment being stepped (see there)."""
        sw = LEFT if fs.leg == "lleg" else RIGHT
        a = self._arrays
        j0 = self._tick - self._origin  # the next sample handed out
        base = seg.start_tick - self._origin  # the segment's first sample
        j1 = base + seg.n_ticks
        p, R, support, zmp = a["p"].copy(), a["R"].copy(), a["support"].copy(), a["zmp"].copy()
        if landed:
            q_dst = q_of(fs)
            p[sw, j0:j1] = (x_m, y_m, q_dst[2])
            R[sw, j0:j1] = rpy_matrices(q_dst[None, 3:])[0]
            support[j0:j1] = BOTH
        else:
            w = self._swing_blend(seg, j0)
            p[sw, j0:j1, 0] += w * (x_m - fs.x)
            p[sw, j0:j1, 1] += w * (y_m - fs.y)
        r = a["r"][j0:j1]
        cop = np.einsum("fnij,fj->fni", R[:, j0:j1], self._zmp_offsets)  # (2, n, 3) flat soles
        zmp[j0:j1] = (1.0 - r)[:, None] * (p[RIGHT, j0:j1] + cop[RIGHT]) + r[:, None] * (p[LEFT, j0:j1] + cop[LEFT])
        self._arrays = {**a, "p": read_only(p), "R": read_only(R), "support": read_only(support),
                        "zmp": read_only(zmp)}
        seg.q_end = seg.q_end.copy()
        seg.q_end[sw, :2] = (x_m, y_m)

    def set_zmp(self, zmp_world: np.ndarray) -> None:
        """Overwrite the reference ZMP of the next ticks with `zmp_world` (m, 3) [m], row 0 for the next tick
        (the emergency step plans it from the measured capture point); rows past the plan's end are dropped,
        the plan's own ZMP stays after the m given."""
        self.apply(self.prepare_set_zmp(zmp_world))

