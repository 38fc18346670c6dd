"""A test-only stand-in for the operation layer's walking point: a layer that publishes
`Ports.walk_command` before the AutoBalancer reads it, as the operation layer does in production."""

from __future__ import annotations

from controller.core.layer import Layer, Status
from controller.core.types import Reference, TickContext
from controller.operation.points import WalkCommand


class WalkPointPublisher(Layer):
    """Wraps the layer just before the AutoBalancer (its name and tick are the wrapped layer's) and then
    publishes `command` on the port, every tick, as the operation layer publishes the walking point."""

    def __init__(self, inner: Layer) -> None:
        super().__init__()
        self.inner = inner
        self.name = inner.name  # the chain checks that a layer is called by its slot's name
        self.command: WalkCommand | None = None

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        ref = self.inner.tick(ctx, ref)
        ctx.ports.walk_command = self.command
        return ref

    def status(self) -> Status:
        return self.inner.status()

    def __getattr__(self, name: str):
        return getattr(self.inner, name)


def install(chain, before: str = "ic") -> WalkPointPublisher:
    """Put a publisher in the slot of `before` (the layer ahead of abc in CHAIN_ORDER) and return it."""
    pub = WalkPointPublisher(chain[before])
    chain.layers[before] = pub
    return pub
