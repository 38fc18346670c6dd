"""`recognise`: one image of the narrow camera as the head points now, and the can or the trash box located in
it through the robot's own head-pose estimate (the rendering and the fit off the control thread)."""

from __future__ import annotations

from dataclasses import dataclass, field

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from behaviors.perception.worker import LOCATORS, RECOGNITION_DELAY_S, PendingRecognition, recognition_dict
from behaviors.preview import PreviewEnds

CAMERA = "narrow_left"  # the narrow stereo pair's left camera, with the depth registered to it
#: [s] paced, how late a result may come and still count (a run fails at 1.5 times the nominal duration). The
#: camera process shares the processors with everything but a real-time loop (nice +10 beside a loop that is
#: not SCHED_FIFO, 0 beside one that is); on a machine kept busy by other work (a CI run's software-GL browser
#: beside the console) a recognition of 0.1-0.2 s of processor time took over 3 s of wall time, and a 2 s
#: allowance failed the locate_can of a CI run.
RECOGNITION_LATE_S = 6.0


@dataclass(frozen=True)
class RecogniseParams(BehaviorParams):
    object: str = field(default="can", metadata={"unit": "-", "choices": tuple(LOCATORS), "doc": "what to locate"})
    require: bool = field(default=True, metadata={"unit": "-", "doc": "fail when it is not in the image"})


class Recognise(Behavior):
    name = "recognise"
    Params = RecogniseParams
    summary = "Locate the can or the trash box in the narrow camera's image as the head points now"

    def nominal_duration_s(self) -> float:
        return RECOGNITION_DELAY_S + RECOGNITION_LATE_S

    def preview(self, ctx: Context, predicted, into, phase: str):
        raise PreviewEnds(f"what follows depends on recognising the {self.params.object} in the camera's image")

    def start(self, ctx: Context) -> None:
        self.pending = PendingRecognition(ctx.commands, CAMERA, self.params.object)
        self.found: dict | None = None

    def step(self, ctx: Context) -> Output:
        got = self.pending.poll(ctx.elapsed_s)
        if got is None:
            return NOTHING
        recognition, intrinsics = got
        if recognition is None:
            message = f"no {self.params.object} in the image"
            if self.params.require:
                return self.fail(message, found=False)
            return self.succeed(message, found=False)
        self.found = recognition_dict(recognition, intrinsics)
        p = self.found["position_m"]
        return self.succeed(f"{self.params.object} at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m", found=True,
                            recognition=self.found)

    def stop(self, ctx: Context) -> None:
        self.pending.cancel()
