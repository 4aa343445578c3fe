"""Request and response models of the HTTP service (pydantic v2), i.e. its OpenAPI schema.

The tableau's JSON Schema (``schemas/tableau-1.schema.json``, checked by :mod:`bootmap.tableau`) stays the
single source of truth; :class:`TableauIn` describes the same documents for OpenAPI, and
tests/service/test_models.py checks that the two accept and refuse the same documents. Request models are
strict: no coercion (``false`` is not 0, ``"1"`` is not 1), unknown fields refused, no NaN or Infinity.
Optional fields may be left out but not sent as ``null``, as in the JSON Schema.
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal, Union

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    JsonValue,
    StrictInt,
    StrictStr,
    WithJsonSchema,
    model_validator,
)

from ..tableau import FORMAT

STRICT = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)
# clingo holds strings as C strings: a label "a\u0000b" would reach the solver as "a", the same view as
# "a\u0000c". The JSON Schema refuses NUL in labels, and so does this model.
NO_NUL = "^[^\\x00]*$"


def _no_default(schema: dict) -> None:
    # An optional field that must not be null: absent is allowed, so the default (None) is not a value
    # a client may send, and the schema should not advertise it.
    schema.pop("default", None)


def optional(**kw: Any) -> Any:
    """A field that may be left out but, when present, must have its type (never null)."""
    return Field(None, json_schema_extra=_no_default, **kw)


def _integral(x: float) -> float:
    if not x.is_integer():
        raise ValueError("should be an integer")
    return x


def _fits_a_float(x: int) -> int:
    # The docs promise integers too large for a float are refused: a 4,000-digit truth is no dstate id.
    try:
        float(x)
    except OverflowError:
        raise ValueError("too large: more than a float can hold") from None
    return x


# JSON Schema's "integer" is a mathematical integer: 3.0 is one. Strict pydantic would refuse it.
IntegerValued = Annotated[Union[Annotated[StrictInt, AfterValidator(_fits_a_float)],
                                Annotated[float, AfterValidator(_integral)]],
                          WithJsonSchema({"type": "integer"})]
# A sense value: bounded, so that squared distances between images (k-means, recognition) stay finite.
SENSE_MAX = 1e9
SenseValue = Annotated[float, Field(ge=-SENSE_MAX, le=SENSE_MAX)]


class TurnAction(BaseModel):
    """Turn in place: negative angles turn right (clockwise), positive left; near +-180 turns around."""

    model_config = STRICT
    type: Literal["turn"]
    angle_deg: float = Field(ge=-360, le=360, description="Degrees; negative right, positive left.")


class TravelAction(BaseModel):
    """Travel along a path to the next dstate, with the net heading change of a curved path."""

    model_config = STRICT
    type: Literal["travel"]
    distance_m: float = Field(gt=0, le=100_000, description="Distance travelled, metres.")
    heading_change_deg: float = optional(ge=-360, le=360, description="Net heading change, degrees (default 0).")


Action = Annotated[Union[TurnAction, TravelAction], Field(discriminator="type")]


class StepIn(BaseModel):
    """One time point: the view (or image) at a dstate, and the action to the next one."""

    model_config = ConfigDict(**STRICT, json_schema_extra={"anyOf": [{"required": ["view"]},
                                                                      {"required": ["image"]}]})
    view: StrictStr = optional(min_length=1, max_length=200, pattern=NO_NUL,
                               description="The view label (a cluster of images); any text but NUL.")
    action: Action = optional(description="The action to the next step; every step but the last has one.")
    image: list[SenseValue] = optional(min_length=1, description="The sense vector at this dstate "
                                                                 "(e.g. 180 laser ranges in metres), values within +-1e9.")
    truth: Union[Annotated[StrictStr, Field(max_length=200, pattern=NO_NUL)], IntegerValued] = optional(
        description="The true dstate id, for evaluation only: an integer, or at most 200 characters, no NUL.")
    pose: list[float] = optional(min_length=3, max_length=3, description="[x, y, theta], for evaluation only.")
    odometry: list[float] = optional(min_length=3, max_length=3,
                                     description="The robot's own dead-reckoned [x, y, theta] at this dstate.")

    @model_validator(mode="after")
    def _view_or_image(self) -> "StepIn":
        if self.view is None and self.image is None:
            raise ValueError("a step needs a view or an image")
        return self


class ResolutionIn(BaseModel):
    """The step the robot's odometry recorded readings at; where left out, read from the readings."""

    model_config = STRICT
    distance_m: float = optional(gt=0, le=1, description="A travel's distance, metres (a centimetre: 0.01).")
    angle_deg: float = optional(gt=0, le=10, description="An angle, degrees (a tenth of a degree: 0.1).")


class MetaIn(BaseModel):
    """Run information, free-form but for the keys the resolver reads."""

    model_config = ConfigDict(extra="allow", strict=True, allow_inf_nan=False)
    __pydantic_extra__: dict[str, JsonValue]  # the free-form keys: any JSON
    resolution: ResolutionIn = optional(description="The resolution of the robot's readings.")


class TableauIn(BaseModel):
    """A tableau, format ``bootmap.tableau/1``: the robot's experience as steps (see /schemas/tableau)."""

    model_config = STRICT
    format: Literal["bootmap.tableau/1"] = Field(description=f"Always {FORMAT!r}.")
    world: StrictStr = optional(max_length=200, pattern=NO_NUL,
                                description="Name of the world the run came from (informational).")
    meta: MetaIn = optional(description="Run information: free-form, but for the keys the resolver reads.")
    steps: list[StepIn] = Field(min_length=1)


class AppendIn(BaseModel):
    """Steps to add to a stored tableau: exploration went on."""

    model_config = STRICT
    action: Action = Field(description="The action from the stored tableau's last step to the first new one.")
    steps: list[StepIn] = Field(min_length=1, description="The new steps, as in a tableau: every step but the "
                                                          "last has an action.")


# A time point (t3 or 3) or a dstate of the tableau's map (S4).
AssertedPoint = Union[Annotated[StrictStr, Field(pattern=r"^(t?[0-9]{1,9}|S[0-9]{1,9})$")],
                      Annotated[StrictInt, Field(ge=0, le=10**9)]]


class AssertionIn(BaseModel):
    """A person's word about the map: two time points (or dstates of the map as it stands) are one dstate
    (``same``: a manual loop closure) or not (``apart``); hard, or soft at a cost (a dstate costs 4)."""

    model_config = ConfigDict(**STRICT, json_schema_extra={"oneOf": [{"required": ["same"]},
                                                                     {"required": ["apart"]}]})
    same: list[AssertedPoint] = optional(min_length=2, max_length=2,
                                         description="Two time points (t3 or 3) or dstates (S4) that are one dstate.")
    apart: list[AssertedPoint] = optional(min_length=2, max_length=2,
                                          description="Two time points or dstates that are different dstates.")
    soft: bool = Field(False, description="Prefer it rather than require it: kept unless breaking it saves more "
                                          "than its cost.")
    cost: int = optional(ge=1, le=1000, description="What breaking a soft assertion costs (default 5; a dstate "
                                                     "costs 4).")
    note: str = optional(max_length=2000, pattern=NO_NUL, description="Why, in the person's words.")


class RecogniseIn(BaseModel):
    """An image to recognise."""

    model_config = STRICT
    image: list[SenseValue] = Field(min_length=1, description="As many values as the stored tableau's images, "
                                                              "each within +-1e9.")


# ---------------------------------------------------------------------------------------------------
# Responses
# ---------------------------------------------------------------------------------------------------

class Out(BaseModel):
    model_config = ConfigDict(extra="forbid")


class MapSummary(Out):
    dstates: int
    places: int
    paths: int
    proved_minimal: bool
    minimal_maps: int = Field(description="Minimal maps found, up to the server's cap.")
    unique: bool = Field(description="Exactly one minimal map explains the tableau.")
    minimal_maps_capped: bool
    levels: list[str]
    found_by: str = Field(description="How the map was found: 'fewest dstates' (the paper's minimal map) or "
                                      "'loop closing' (odometry's merges every axiom accepts).")


class StepRow(Out):
    """One row of the annotated tableau, as in the paper's table (6)."""

    t: int
    view: str
    dstate: str
    place: str | None
    path: str | None
    dir: Literal["pos", "neg"] | None
    action: str


class SuspectStep(Out):
    """A time point whose view the map takes as a misread (a misclustered image)."""

    t: int
    observed: str = Field(description="The view the tableau gives at t.")
    expected: str = Field(description="The view of the dstate the map puts t at.")
    cost: int | None = Field(description="What taking it as a misread cost, where a dstate costs 4.")


class RetypedStep(Out):
    """An action the map takes as mistyped: its reading lay far from its learned type's angle."""

    t: int
    kind: Literal["turn", "travel"]
    measured_deg: float = Field(description="What odometry read (a turn's angle, a travel's heading change).")
    learned_deg: int = Field(description="The angle of the type it was learned as.")
    abduced_deg: int = Field(description="The angle the axioms saw instead.")
    cost: int | None = Field(description="What taking it as mistyped cost, where a dstate costs 4.")


class DstateOut(Out):
    view: str
    heading_deg: int | None
    place: str | None
    path: str | None
    dir: Literal["pos", "neg"] | None


class ActionTypeOut(Out):
    """One of the robot's action types: the angle the axioms saw, and what odometry measured for it."""

    kind: Literal["turn", "travel"]
    angle_deg: int = Field(description="The angle the axioms saw (a turn's angle, a travel's heading change).")
    count: int = Field(description="Actions of this type in the tableau.")
    measured_mean_deg: float
    measured_sd_deg: float
    resolution_deg: float = Field(description="The step its kind's angles were recorded at (0: continuous), "
                                              "as the tableau states it (meta.resolution) or its readings show.")
    exact: bool = Field(description="Its kind's readings were taken as exact primitives (every value a type), "
                                    "not as noisy readings clustered into types.")
    read_from_walls: int = Field(0, description="Of its actions, those whose angle was read from the walls in the "
                                                "laser images at their ends (the tableau's meta.laser), not odometry.")


class LengthTypeOut(Out):
    """One length of the robot's travels: the label the axioms saw, and what odometry measured for it."""

    length_dm: int = Field(description="The label the axioms saw: the type's mean length in decimetres.")
    count: int = Field(description="Travels of this length in the tableau.")
    measured_mean_m: float
    measured_sd_m: float
    resolution_m: float = Field(description="The step the distances were recorded at (0: continuous).")
    exact: bool = Field(description="The distances were taken as exact (every value a type), not as noisy "
                                    "readings clustered into lengths.")


class MapOut(Out):
    """The minimal map: dstates, places, paths and how they relate, and every step annotated."""

    revision: int = Field(description="The tableau revision this map explains.")
    theory: str = Field(description="Id of the axiom snapshot the map was solved with (see /axioms).")
    views_from_images: int | None = Field(description="Views found by clustering the images (k), or null "
                                                      "when the tableau gave view labels.")
    summary: MapSummary
    steps: list[StepRow]
    dstates: dict[str, DstateOut]
    places: dict[str, list[str]] = Field(description="Place -> its dstates.")
    paths: dict[str, list[str]] = Field(description="Path -> its places in pos order.")
    on: list[list[str]] = Field(description="[place, path] pairs.")
    order: list[list[str]] = Field(description="[path, before, after] along pos.")
    right_of: list[list[str]] = Field(description="[place, path]: the place is right of the path facing pos.")
    left_of: list[list[str]] = Field(description="[place, path]: the place is left of the path facing pos.")
    alternatives: list[list[str]] = Field(description="The dstate of each time point in the other minimal maps.")
    action_types: list[ActionTypeOut] = Field(description="The robot's action types, learned from the tableau's "
                                                         "angles (or its angles rounded to the server's quantum).")
    length_types: list[LengthTypeOut] = Field(description="The lengths of the robot's travels, learned from the "
                                                          "tableau's distances.")
    suspect_steps: list[SuspectStep] = Field(description="Time points whose views the map takes as misreads: "
                                                         "explaining them as seen needs far more dstates.")
    retyped_steps: list[RetypedStep] = Field(description="Actions the map takes as mistyped: read far from "
                                                          "their learned type, and typed as its neighbour.")
    confidence: dict[str, Any] | None = Field(None, description="What the minimal maps found agree on: "
                                              "minimal_maps, capped, settled (the share of time points whose "
                                              "dstate every one of them agrees on), and per dstate and place "
                                              "in_maps (in how many it is the same) and, per dstate, "
                                              "confusable (the time points it could still be one with); null "
                                              "for a loop-closed map.")
    stats: dict[str, Any] = Field(description="Solver figures (seconds, bounds tried).")


class AssertionOut(Out):
    """A stored assertion: what was said, by which token, when."""

    id: int
    same: list[str] | None = Field(None, description="The two time points said to be one dstate.")
    apart: list[str] | None = Field(None, description="The two time points said to be different dstates.")
    soft: bool
    cost: int | None = Field(description="What breaking it costs (soft ones), else null.")
    note: str | None
    by: str = Field(description="The token (its name) that made it.")
    at: datetime = Field(description="When it was made.")
    held: bool = Field(description="Whether the stored map does what it says (a soft one may be broken).")


class AssertionList(Out):
    """A tableau's assertions, oldest first, and whether the stored map honours each."""

    assertions: list[AssertionOut]


class MapDiffOut(Out):
    """What changed in the map: dstates, places and paths joined or split (named as in each map)."""

    changed: bool
    joined: list[dict[str, Any]] = Field(description="{now, was}: a dstate of the new map made of several of the old.")
    split: list[dict[str, Any]] = Field(description="{was, now}: a dstate of the old map now several.")
    places_joined: list[dict[str, Any]]
    places_split: list[dict[str, Any]]
    paths_joined: list[dict[str, Any]]
    paths_split: list[dict[str, Any]]
    renamed: dict[str, str] = Field(description="Dstates unchanged but for their name: old -> new.")
    dstates: list[int] = Field(description="[before, after].")
    places: list[int]
    paths: list[int]


class AssertedOut(Out):
    """The tableau's map re-solved after its assertions changed, what changed, and the assertions now."""

    assertion: AssertionOut | None = Field(description="The assertion made (null after a removal).")
    assertions: list[AssertionOut]
    diff: MapDiffOut
    map: MapOut


class MinimalMap(Out):
    dstates: int
    dstate_of: list[str] = Field(description="The dstate of each time point.")


class MinimalMaps(Out):
    """Every minimal map found: more than one when the experience does not tell them apart."""

    unique: bool
    capped: bool = Field(description="The enumeration stopped at the server's cap; there may be more.")
    maps: list[MinimalMap]


class TableauInfo(Out):
    id: int
    revision: int
    steps: int
    created: datetime
    updated: datetime
    views_from_images: int | None
    public: bool = Field(description="Anyone may read it; only its owner or an admin changes it.")


class TableauSharing(BaseModel):
    """Whether anyone may read a tableau and its maps."""

    model_config = STRICT
    public: bool


class TokenIn(BaseModel):
    """A new API token's name, and whether it is an admin's."""

    model_config = STRICT
    name: StrictStr = Field(min_length=1, max_length=100, pattern="^[A-Za-z0-9_.@-]+$")
    admin: bool = False


class TokenCreated(Out):
    id: int
    name: str
    admin: bool
    token: str = Field(description="The token, shown this once: only its hash is stored.")


class TableauCreated(TableauInfo):
    map: MapOut


class TableauOut(TableauInfo):
    tableau: TableauIn


class TableauListItem(Out):
    id: int
    revision: int
    steps: int
    dstates: int
    places: int
    paths: int
    updated: datetime


class TableauList(Out):
    total: int
    items: list[TableauListItem]


class Recognition(Out):
    dstate: str = Field(description="The dstate of the nearest stored image.")
    distance: float = Field(description="Euclidean distance to it: large means an unfamiliar image.")
    view: str
    place: str | None


class RuleCited(Out):
    """A rule of the theory as a proof cites it."""

    name: str = Field(description="Its '%! name' label ('unnamed' without one).")
    level: str = Field(description="Its level (file stem), or 'core'.")
    file: str
    line: int


class ProofNodeOut(Out):
    """An atom of a proof and how it holds: derived by ``rule`` from ``premises``, observed at tableau
    ``step``, or neither (the supposition, or which dstate a time point is at)."""

    atom: str
    text: str = Field(description="The atom in words.")
    rule: RuleCited | None = None
    step: int | None = None
    premises: list["ProofNodeOut"] = Field(default_factory=list)


ProofNodeOut.model_rebuild()


class FailureOut(Out):
    """An axiom the supposition breaks, and why its premises hold."""

    rule: RuleCited
    premises: list[ProofNodeOut]
    merged: list[list[int]] = Field(description="Time points the supposition puts together.")


class AlternativeOut(Out):
    map: int
    a: str
    b: str
    apart: bool


class ExplanationOut(Out):
    """Are time points a and b one dstate, and why (as `bootmap why` explains it)."""

    a: int = Field(description="The time point a stands for.")
    b: int
    dstates: list[str] = Field(description="Their dstates in the minimal map with these levels.")
    verdict: Literal["different", "same", "undecided"]
    sentence: str
    evidence: list[int] = Field(description="A subset-minimal set of steps that alone forces them apart.")
    axioms: list[RuleCited] = Field(description="The constraints the contradiction needs.")
    failures: list[FailureOut]
    rules_cited: list[str]
    agree_steps: int
    suggestion: list[str] = Field(description="Experience that would test a 'same' verdict.")
    alternatives: list[AlternativeOut]
    levels: list[str]
    found_by: str = Field("fewest dstates", description="The map explained: 'fewest dstates' (the minimal map) "
                                                        "or 'loop closing' (a log's tableau).")
    joins: list[str] = Field([], description="Loop closing, 'same': the joins that made them one dstate, each "
                                             "proposed by odometry or forced by determinism.")
    supposed: Literal["same", "apart"] = Field("same", description="What the proof supposes and the axioms refute: "
                                               "that a and b are one dstate ('same': a 'different' verdict) or two "
                                               "('apart': a 'same' verdict, as a clash with a person's apart is).")
    stats: dict[str, Any]
    text: str = Field(description="The whole explanation as text.")


class HypothesisOut(Out):
    at: str = Field(description="The dstate this minimal map puts the robot at now.")
    predicts: list[str | None] = Field(description="The view it predicts after each planned action "
                                                   "(null where it cannot say).")


class RehearsalOut(Out):
    """What to do when the minimal maps disagree (as `bootmap rehearse` plans it)."""

    kind: Literal["nothing", "distinguish", "partial", "test", "explore"] = Field(
        description="nothing: the map is unique; distinguish: the plan tells every map apart; partial: some "
                    "pairs; test: some maps predict views where others cannot say; explore: it leads to an "
                    "action not yet taken there.")
    actions: list[str] = Field(description="The actions to take from where the robot is now.")
    separated_pairs: int
    pairs: int
    hypotheses: list[HypothesisOut] = Field(description="Per minimal map: where the robot is, what it predicts.")
    settled_now: float = Field(1.0, description="The share of time points every minimal map puts at one dstate.")
    settled_after: float = Field(1.0, description="... after the plan, whatever the robot sees (at worst).")
    text: str = Field(description="The plan as text.")


class RuleOut(Out):
    name: str
    line: int
    text: str


class AxiomFile(Out):
    level: str = Field(description="The level (file stem), or 'core' for the search layout.")
    file: str = Field(description="Path relative to the axiom directory.")
    rules: list[RuleOut]


class AxiomsOut(Out):
    theory: str = Field(description="Id of this snapshot (a hash of the files).")
    directory: str = Field(description="The axiom directory's name (not its path on the server).")
    loaded: datetime
    levels: list[str]
    files: list[AxiomFile]


class Health(Out):
    status: Literal["ok"]
    version: str
    theory: str
    solvers: int = Field(description="Solver processes alive.")
    solves_running: int
    solves_waiting: int


class Problem(BaseModel):
    """RFC 9457 problem details; ``errors`` lists every invalid field when there are several."""

    model_config = ConfigDict(extra="allow")
    type: str
    title: str
    status: int
    detail: str
    instance: str | None = None
    field: str | None = Field(None, description="The field to fix, e.g. steps[3].action.angle_deg.")
    errors: list[dict[str, Any]] | None = None
