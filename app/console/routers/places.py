"""Named places ([OP] II, VI): the points the robot knows by name (the scene's known table and trash box, the
objects it has located), so that an operator may say `look_at table` instead of three coordinates."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Path
from pydantic import BaseModel, Field

from app.console.deps import ServiceDep
from app.console.errors import errors
from behaviors.places import ALIASES

router = APIRouter(prefix="/api/places", tags=["behaviors"])

PlaceName = Annotated[str, Path(max_length=64, description="a place's name or alias, e.g. table, box, can")]


class PlaceDoc(BaseModel):
    name: str = Field(description="the place")
    position_m: list[float] = Field(description="its point, world [m] (x, y, z)")
    source: Literal["known", "estimated", "confirmed", "corrected"] = Field(
        description="'known': the scene's known place (the table's, the trash box's); otherwise the object's latest "
                    "recognition and what the operator said of it")


class PlacesDoc(BaseModel):
    places: dict[str, PlaceDoc] = Field(description="place -> its point and where it comes from")
    aliases: dict[str, str] = Field(description="other names for a place (alias -> place)")


def _doc(place) -> PlaceDoc:
    return PlaceDoc(name=place.name, position_m=list(place.position_m), source=place.source)


@router.get("", response_model=PlacesDoc, responses=errors(),
            summary="The places the robot knows by name: the scene's known ones and the objects it located")
def list_places(service: ServiceDep) -> PlacesDoc:
    found = service.places()
    return PlacesDoc(places={n: _doc(p) for n, p in found.items()},
                     aliases={a: n for a, n in ALIASES.items() if n in found})


@router.get("/{name}", response_model=PlaceDoc, responses=errors(404, e404="no such place (the valid ones are "
                                                                            "listed)"),
            summary="One place by name or alias: its point (world [m])")
def get_place(name: PlaceName, service: ServiceDep) -> PlaceDoc:
    return _doc(service.place(name))
