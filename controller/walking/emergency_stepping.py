"""The capture-point emergency steps the AutoBalancer takes: when, from which feet, the per-tick re-plan and
landing, another step when one was not enough, and the records its status shows."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.types import BalanceEstimate, GaitState, Ports, StepInProgress, TickContext
from controller.kinematics.rotations import homogeneous
from controller.walking.auto_balancer_params import FEET, SWING_FOOT_LOADED_N, AutoBalancerParams, EmergencyStepRecord
from controller.walking.emergency_step import EmergencyStepParams, EmergencyStepPlan, SupportRegion, swing_leg_for
from controller.walking.footsteps import Footstep
from controller.walking.gait_generator import GaitGenerator, GaitPatch
from controller.walking.preview_control import PreviewController

#: [-] share of the robot's weight the feet must carry for an emergency step (a robot held in the air does not step)
EMERGENCY_STEP_MIN_LOAD_RATIO = 0.5
#: [-] an emergency step's foot touches down early when it carries this share of the weight after this share of its
#: swing (the force sensor of a foot swung fast reads its inertia: up to 110 N measured 5 cm above the ground)
TOUCHDOWN_LOAD_RATIO = 0.25
TOUCHDOWN_SWING_SHARE = 0.6
#: [s] the swing of a capture step from a walk: the walk's remaining swing, within these (the foot needs time to go
#: where the capture point calls it; a long swing is shortened so the foot lands before the capture point runs away)
CATCH_SWING_S = (0.16, 0.25)
#: [s] after an emergency step's touchdown, a capture point still outside the two soles calls for another step
RESTEP_AFTER_S = 0.05
#: emergency steps one after the other at most (each from the last one's feet)
EMERGENCY_STEPS_IN_A_ROW = 3
#: emergency steps remembered in the status
EMERGENCY_STEPS_KEPT = 10


@dataclass(frozen=True, slots=True)
class PreparedReplan:
    """The emergency step's re-plan of sample k, made after the last tick's command was written (after_write) from
    the ports that tick published: the next tick adopts it if it re-plans the same plan at k from those ports."""

    ports: Ports  # what it read (the next tick's last_ports)
    plan: EmergencyStepPlan  # the live plan, unchanged; `replanned` is its copy, replanned at k
    k: int
    replanned: EmergencyStepPlan
    moved: bool  # replan's result
    gait_op: str | None  # what the gait gets with it: "move" (the landing and the ZMP), "zmp", or None
    zmp: np.ndarray | None  # replanned.zmp(k) for that op
    patch: GaitPatch | None  # the gait's change for that op, None if it must be done in the tick


class EmergencyStepping:
    """The AutoBalancer's capture-point emergency steps, walked by its gait generator: each method that may start
    a step returns True when it did, and the AutoBalancer then sets its walking point and walking stop."""

    def __init__(self, gait: GaitGenerator, dt_s: float, total_mass_kg: float) -> None:
        self.gait = gait
        self.dt_s = dt_s
        self.total_mass_kg = total_mass_kg
        self.plan: EmergencyStepPlan | None = None  # the emergency step being taken
        self.k = 0  # samples of its plan handed out
        self.records: tuple[EmergencyStepRecord, ...] = ()
        self._lifted = False  # the swinging foot has been unloaded in this swing
        self._landing_pending = False  # the plan's landing moved before the swing; the gait's not yet
        self._in_a_row = 0  # emergency steps taken one after the other (the first included)
        self._from_walk = False  # the emergency step in progress caught a walk (it may step again)
        self._support: tuple[object, SupportRegion] | None = None  # (the idle soles it is for, the region)
        self._step_port: StepInProgress | None = None  # the last Ports.step published (reused while it holds)

    @property
    def active(self) -> bool:
        """An emergency step is in progress."""
        return self.plan is not None

    def drop(self) -> None:
        """Forget the step in progress (the hard e-stop's stop from rest replaces it)."""
        self.plan = None

    def check_standing(self, ctx: TickContext, g: GaitState | None, params: AutoBalancerParams,
                       preview: PreviewController) -> bool:
        """Standing: step when the capture point the Stabilizer measured last tick is farther than the margin
        outside the support polygon of the two soles (and the feet carry the robot)."""
        bal = ctx.last_ports.balance
        if bal is None or g is None or g.walking or (ctx.hold and not ctx.last_ports.landing):
            return False
        support = self._support
        if support is None or support[0] is not g.p_rsole_world:  # the idle soles' arrays: rebuilt when they move
            support = self._support = (g.p_rsole_world, SupportRegion.of_soles(
                (g.p_rsole_world, g.R_rsole_world), (g.p_lsole_world, g.R_lsole_world)))
        loads = self._loads_if_outside(ctx, bal, support[1], params)
        if loads is None:
            return False
        self._start(ctx, bal, *loads, params.emergency_step, preview)
        return True

    def _loads_if_outside(self, ctx: TickContext, bal: BalanceEstimate, region: SupportRegion,
                          params: AutoBalancerParams) -> tuple[float, float] | None:
        """The feet's vertical forces (right, left) [N] when the capture point is farther than the margin outside
        `region` and the feet carry the robot (a step is called for); None otherwise."""
        cx, cy = bal.cp_world_xy.tolist()
        if region.outside_m(cx, cy) <= params.emergency_step.cp_margin_m:
            return None
        rows = ctx.estimate.wrenches_ext.tolist()
        fz_r, fz_l = rows[FEET[0]][2], rows[FEET[1]][2]
        if fz_r + fz_l < EMERGENCY_STEP_MIN_LOAD_RATIO * self.total_mass_kg * GRAVITY_M_S2:
            return None
        return fz_r, fz_l

    def catch(self, ctx: TickContext, params: AutoBalancerParams, preview: PreviewController) -> bool:
        """The capture-point flag rose while walking: the walk ends where it is. A foot in the air lands where the
        capture point will be, as the emergency step does (the swing's time kept, within CATCH_SWING_S); with both
        feet down the robot stands there (False), and the standing emergency step follows if the ankles cannot
        hold it."""
        bal = ctx.last_ports.balance
        swing_left = self.gait.swing_samples_left()
        support = self.gait.abort()
        if support == "both" or swing_left == 0:
            return False  # the COG plan goes on to rest over the feet; the Stabilizer's feedback takes the push
        preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])
        swing_leg = "lleg" if support == "rleg" else "rleg"
        T_swing = self.gait.T_world_lfoot if swing_leg == "lleg" else self.gait.T_world_rfoot
        T_stance = self.gait.T_world_rfoot if swing_leg == "lleg" else self.gait.T_world_lfoot
        p = params.emergency_step
        lo, hi = CATCH_SWING_S
        swing_s = min(max(swing_left * self.dt_s, lo), hi)
        height = float(T_swing[2, 3] - T_stance[2, 3])  # the foot is this high already: the arc adds the rest
        p = p.replaced(initial_double_support_s=self.dt_s,
                       step_time_s=max(swing_s / (1.0 - p.double_support_ratio), 0.2),
                       step_height_m=min(max(p.step_height_m - height, 0.01), p.step_height_m))
        rows = ctx.estimate.wrenches_ext.tolist()
        self._start(ctx, bal, rows[FEET[0]][2], rows[FEET[1]][2], p, preview, swing_leg=swing_leg)
        self._from_walk = True
        return True

    def step_port(self, ctx: TickContext, params: AutoBalancerParams) -> StepInProgress | None:
        """Ports.step this tick: the emergency step until it ends, or a walk's swing while its foot is in the air."""
        if self.active:
            samples, catching, cut_s = self.plan.touchdown_k - self.k, True, None
        else:
            samples, catching = self.gait.swing_samples_left(), False
            if samples == 0:
                self._step_port = None
                return None
            cut_s = self.cut_swing_s(params, samples)
        touchdown_s = ctx.time_s + samples * ctx.dt_s
        last = self._step_port
        if last is None or (last.catching, last.cut_swing_s) != (catching, cut_s) \
                or abs(last.touchdown_time_s - touchdown_s) > 0.5 * ctx.dt_s:
            last = self._step_port = StepInProgress(touchdown_s, catching, cut_s)
        return last

    def cut_swing_s(self, params: AutoBalancerParams, swing_samples_left: int) -> float | None:
        """How long [s] after the next tick a walk's swing with that many samples left would land if the hard
        e-stop's landing cut it short (`cut`: seen a tick after the press, then at most CATCH_SWING_S's longest);
        None when it would not be cut (it lands within that anyway, or the emergency step is off)."""
        if not params.emergency_step.enabled or swing_samples_left * self.dt_s <= CATCH_SWING_S[1]:
            return None
        return CATCH_SWING_S[1] + 2.0 * self.dt_s

    def cut(self, ctx: TickContext, params: AutoBalancerParams, preview: PreviewController) -> bool:
        """The hard e-stop lets the step in progress land before it freezes (Ports.landing): a walk's swing planned
        down later than CATCH_SWING_S allows is cut short as `catch` cuts it, the foot landing where the capture
        point will be, so that the robot freezes on both feet, not on one (soak seed 10705: frozen in the air, it
        tipped toward its swing foot and a release before that foot had touched could not catch it). False when
        nothing was cut (a swing landing sooner, double support, the emergency step off, no balance estimate)."""
        if ctx.last_ports.balance is None or self.cut_swing_s(params, self.gait.swing_samples_left()) is None:
            return False
        return self.catch(ctx, params, preview)

    def _start(self, ctx: TickContext, bal: BalanceEstimate, fz_r: float, fz_l: float,
               step_params: EmergencyStepParams, preview: PreviewController, swing_leg: str | None = None) -> None:
        """Plan the step from the feet where the (idle) gait has them and start it this tick; `swing_leg`: the foot
        in the air of a walk that ended (else the leg the capture point calls for)."""
        gait = self.gait
        rfoot, lfoot = Footstep.from_T("rleg", gait.T_world_rfoot), Footstep.from_T("lleg", gait.T_world_lfoot)
        leg = swing_leg
        if leg is None:
            yaw = math.atan2(math.sin(rfoot.yaw) + math.sin(lfoot.yaw), math.cos(rfoot.yaw) + math.cos(lfoot.yaw))
            dx = float(bal.cp_world_xy[0]) - 0.5 * (rfoot.x + lfoot.x)
            dy = float(bal.cp_world_xy[1]) - 0.5 * (rfoot.y + lfoot.y)
            c, s_ = math.cos(yaw), math.sin(yaw)
            leg = swing_leg_for((c * dx + s_ * dy, -s_ * dx + c * dy), fz_r, fz_l)
        self._begin(ctx, bal, self._plan(bal, rfoot, lfoot, leg, step_params), preview)

    def _plan(self, bal: BalanceEstimate, rfoot: Footstep, lfoot: Footstep, leg: str,
              step_params: EmergencyStepParams) -> EmergencyStepPlan:
        stance, swing = (rfoot, lfoot) if leg == "lleg" else (lfoot, rfoot)
        return EmergencyStepPlan(step_params, self.dt_s, stance, swing, bal.cp_world_xy, bal.zmp_world, bal.omega_1_s)

    def _begin(self, ctx: TickContext, bal: BalanceEstimate, plan: EmergencyStepPlan,
               preview: PreviewController) -> None:
        """Walk `plan` from this tick (the gait idle, its feet where the plan starts)."""
        gait, leg = self.gait, plan.swing.leg
        gait.plan(plan.footsteps(), params=plan.gait_params(gait.params))
        gait.set_zmp(plan.zmp(0))
        preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])
        again = self.plan is not None
        self._in_a_row = self._in_a_row + 1 if again else 1
        self._from_walk = self._from_walk and again
        self.plan, self.k = plan, 0
        self._landing_pending = False
        self.records = (*self.records, EmergencyStepRecord(
            leg=leg, time_s=ctx.time_s, cp_at_trigger=tuple(bal.cp_world_xy.tolist()),
            landing=tuple(plan.landing_xy.tolist()), landed=False, landed_early=False))[-EMERGENCY_STEPS_KEPT:]
        ctx.ports.emergency_step = True

    def prepare(self, ports: Ports) -> PreparedReplan | None:
        """The re-plan of the next tick's sample from the capture point this tick measured (ports.balance), made
        once the command is out (AutoBalancer.after_write); None when there is nothing worth preparing. It changes
        nothing."""
        plan, bal = self.plan, ports.balance
        if plan is None or bal is None or not self.gait.walking:
            return None
        k = self.k
        if k >= plan.n_touchdown or plan.landed_k is not None:
            return None  # replan does nothing any more: nothing worth preparing
        new, moved = plan.replanned(k, bal.cp_world_xy)
        op = self._gait_op(plan, k, moved, new.landing_xy is not plan.landing_xy)
        zmp = patch = None
        if op is not None:
            zmp = new.zmp(k)
            patch = self.gait.prepare_set_zmp(zmp) if op == "zmp" else \
                self.gait.prepare_move_swing({1: tuple(new.landing_xy.tolist())}, zmp)
        return PreparedReplan(ports, plan, k, new, moved, op, zmp, patch)

    def _gait_op(self, plan: EmergencyStepPlan, k: int, moved: bool, foot_moved: bool) -> str | None:
        """What the gait gets after a re-plan of sample k (no touchdown): "move" (the landing with the ZMP), "zmp"
        (the ZMP alone) or None; the landing reaches the gait once, the tick before the swing (what samples the
        foot's path before it is not used; a move then resamples the whole step, the last one is what counts)."""
        if foot_moved and k < plan.n_lift - 1:
            return "zmp" if moved else None
        if foot_moved or (self._landing_pending and k >= plan.n_lift - 1):
            return "move"
        return "zmp" if moved else None

    def tick(self, ctx: TickContext, params: AutoBalancerParams, preview: PreviewController,
             last_gait: GaitState | None, prepared: PreparedReplan | None = None) -> bool:
        """One tick of the emergency step before the gait samples it: the landing follows the measured capture
        point (until shortly before touchdown), a foot that touches down early lands where it is, the COG plan
        restarts from the measured COG until the foot is down; the plan's end ends it (standing, the feet apart).
        The re-plan is `prepared`'s when it was made from this tick's inputs (after_write). True when another
        step began instead (_step_again)."""
        plan, k = self.plan, self.k
        if not self.gait.walking:
            self.plan = None
            self._update_record(plan, landed=True)
            return False
        ctx.ports.emergency_step = True
        bal = ctx.last_ports.balance
        if self._step_again(ctx, plan, k, params, preview, last_gait):
            return True
        ready = None  # the prepared re-plan, adopted
        if plan.swinging(k) and self._touched_down(ctx, plan, k):
            plan.land(k, self._measured_sole_xy(ctx, plan))
            moved, landed = True, True
            op = self._gait_op(plan, k, moved, True)
        elif bal is not None:
            landing = plan.landing_xy
            if prepared is not None and prepared.ports is ctx.last_ports and prepared.plan is plan \
                    and prepared.k == k and prepared.replanned.revision == plan.revision + 1:
                plan.adopt(prepared.replanned)
                moved, ready = prepared.moved, prepared
            else:
                moved = plan.replan(k, bal.cp_world_xy)
            op, landed = self._gait_op(plan, k, moved, plan.landing_xy is not landing), False
            if plan.landing_xy is not landing and k < plan.n_lift - 1:
                self._landing_pending = True
        else:
            moved, landed, op = False, False, None
        if ready is not None and ready.gait_op != op:
            ready = None  # the same decision from the same state: never, but then the gait's part is done here
        if op == "move":  # the footstep and the plan's ZMP in one (the ZMP the moved feet give would be overwritten)
            self._landing_pending = False
            if ready is None or ready.patch is None or not self.gait.apply(ready.patch):
                zmp = plan.zmp(k) if ready is None else ready.zmp
                self.gait.move_footsteps({1: tuple(plan.landing_xy.tolist())}, landed=landed, zmp_world=zmp)
        elif op == "zmp":
            if ready is None or not self.gait.apply(ready.patch):
                self.gait.set_zmp(plan.zmp(k) if ready is None else ready.zmp)
        if moved or k == plan.touchdown_k:
            self._update_record(plan, landed=k >= plan.touchdown_k)
        if bal is not None and k < plan.touchdown_k:  # the COG plan follows the measured COG until the foot is down
            preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])
        return False

    def _step_again(self, ctx: TickContext, plan: EmergencyStepPlan, k: int, params: AutoBalancerParams,
                    preview: PreviewController, last_gait: GaitState | None) -> bool:
        """A step from a walk (the catch): once the foot is down and the weight shared (RESTEP_AFTER_S), a capture
        point still outside the new support polygon calls for another step, from where the feet are (at most
        EMERGENCY_STEPS_IN_A_ROW). The standing emergency step stays one step (its [MLC] experiments' verdicts)."""
        bal = ctx.last_ports.balance
        if bal is None or not self._from_walk or k < plan.touchdown_k + round(RESTEP_AFTER_S / self.dt_s) \
                or ctx.last_ports.landing or self._in_a_row >= EMERGENCY_STEPS_IN_A_ROW:
            return False
        support = self._support
        if support is None or support[0] is not plan:
            support = self._support = (plan, SupportRegion(plan.support_polygon_after()))
        loads = self._loads_if_outside(ctx, bal, support[1], params)
        if loads is None:
            return False
        # the leg whose landing leaves the capture point predicted at its touchdown least outside the feet
        g = last_gait
        rfoot = Footstep.from_T("rleg", homogeneous(g.p_rsole_world, g.R_rsole_world))
        lfoot = Footstep.from_T("lleg", homogeneous(g.p_lsole_world, g.R_lsole_world))
        again = min((self._plan(bal, rfoot, lfoot, leg, params.emergency_step)
                     for leg in (plan.stance.leg, plan.swing.leg)),
                    key=lambda c: SupportRegion(c.support_polygon_after()).outside_m(*c.cp_touchdown_xy.tolist()))
        self._update_record(plan, landed=True)
        self.gait.abort()
        self._begin(ctx, bal, again, preview)
        return True

    def _touched_down(self, ctx: TickContext, plan: EmergencyStepPlan, k: int) -> bool:
        """The swing foot, in the air before, carries TOUCHDOWN_LOAD_RATIO of the weight late in its swing: it has
        touched the ground early. (A foot that never left the ground is not landing: it is dragged.)"""
        fz = float(ctx.estimate.wrenches_ext[FEET[0 if plan.swing.leg == "rleg" else 1]][2])
        if k == plan.n_lift:
            self._lifted = False
        if fz < SWING_FOOT_LOADED_N:
            self._lifted = True
            return False
        late = k - plan.n_lift >= TOUCHDOWN_SWING_SHARE * (plan.n_touchdown - plan.n_lift)
        return self._lifted and late and fz > TOUCHDOWN_LOAD_RATIO * self.total_mass_kg * GRAVITY_M_S2

    @staticmethod
    def _measured_sole_xy(ctx: TickContext, plan: EmergencyStepPlan) -> tuple[float, float]:
        """Where the swing sole is [m]: the stance sole where the plan has it plus the measured kinematics from it to
        the swing sole (encoders and the KalmanFilter attitude)."""
        pos = ctx.estimate.sensor_pos_from_base.tolist()
        i_sw, i_st = (FEET[0], FEET[1]) if plan.swing.leg == "rleg" else (FEET[1], FEET[0])
        return (plan.stance.x + pos[i_sw][0] - pos[i_st][0], plan.stance.y + pos[i_sw][1] - pos[i_st][1])

    def _update_record(self, plan: EmergencyStepPlan, landed: bool) -> None:
        """The status record of the step in progress (the last one): its landing and whether it is down."""
        if self.records:
            *rest, last = self.records
            self.records = (*rest, dataclasses.replace(
                last, landing=tuple(plan.landing_xy.tolist()), landed=landed, landed_early=plan.landed_k is not None))
