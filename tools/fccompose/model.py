"""The canopy as a constraint system: static Model, changing State (Warp's split; thesis 3, 8 f).

:func:`build_model` reads everything a ``.fcc`` file names (:func:`load_inputs`: OBJ sequences,
single OBJs, weight files, SCN files, RBA folders), then :func:`assemble_model`, which reads no
files, instances every placement and concatenates the florets into one structure-of-arrays system:

- ``Model`` (static): ``tri_indices``, ``edge_indices``, ``hinge_indices`` (global vertex ids),
  per-constraint stiffness, ``vertex_inv_mass`` (0 for the fixed vertices of the weight files),
  ``vertex_floret``, the template frames of every animation (``template_x``, local coordinates,
  scaled by the entry's initial scale) and per-floret tables; plus :meth:`Model.schedule`, which
  gives at any (fractional) frame each floret's developmental time and placement matrix (a
  :class:`Schedule`), and keyword wrappers of the kernels (:mod:`.kernels`) that take a ``Schedule``
  (:meth:`Model.template_positions`, :meth:`Model.rest_values`, :meth:`Model.predict`).
- ``State`` (changing): the positions ``vertex_x``, the last frame completed and which florets
  have emerged, at what size and when; what ``fccompose --resume`` saves and loads
  (:mod:`.compose`). The solver's settings and caches (the control) are
  :class:`inflo.tools.fccompose.compose.Simulation`'s.

Rest values at a time (edge lengths, eq. 3.11; signed dihedral angles, eq. 3.13) are computed
from the two template frames around the floret's developmental time, each mapped through the
linear part of its placement (scale, scene scale; rotation does not change them), and
interpolated linearly (angles along the shorter way, modulo 2 pi).

Placement kinds (SCN, app. C.2) and developmental time u in [0, 1] (template frame u (F - 1)):

- ``ca start end``: u = (frame - start) / (end - start), clamped; static placement.
- ``i value``: u = value for all frames; static placement.
- ``o``: u = 0 (first template frame); static placement.
- ``ta start end x y z``: translated by s (x, y, z), s = (frame - start)/(end - start) clamped;
  develops like ``ca`` over the same frames.
- ``ra start end x y z angle``: rotated by s * angle degrees about the axis (x, y, z) through the
  placement position; develops like ``ca``.
- ``rba start end``: placement of each frame from the RBA files (linear interpolation between
  frames and of sub-steps; a floret absent from a frame takes the nearest frame where it is
  present); develops like ``ca``. The ``rigid body animation`` entry's scale and the placement's
  own SCN scale (a factor: the floret's size relative to its primordium, e.g. ``dimorph``'s ray
  scale; ``phyllotaxis`` writes 1) multiply the RBA scales. The floret *emerges* at the first RBA frame that lists it (:attr:`Floret.birth_frame`,
  the primordium's formation in a dynamic phyllotaxis): before that it is not part of the canopy
  (no collisions, no faces in the output; :class:`inflo.tools.fccompose.compose.Simulation`).

Nested scenes (formats/fcc.md): a placement whose id is a ``rigid body animation`` entry's
instances that entry's scene (a :class:`Level`); its florets carry the chain of outer levels
(:attr:`Floret.outer`) and read their own windows on the inner clock (``frame - shift``, the outer
placements' ``frameStart``). Their matrices are composed in :meth:`Model.matrix` (per floret, not
in the vectorized RBA tables of the top-level ``rba:`` florets).

Weight files list fixed vertex ids: 0-based indices in the OBJ's vertex order, separated by blanks,
commas or line breaks; ``#`` starts a comment.

The model lives in rooms of one concern each, beside this module, which builds it
(:func:`build_model`) and is the import path of every name below:

- :mod:`.system`: the constraint system itself (:class:`Template`, :class:`Floret`,
  :class:`Level`, :class:`Model`, :class:`Schedule`, :class:`State`) and each placement's matrix
  over time;
- :mod:`.inputs`: reading the files (:func:`load_inputs`);
- :mod:`.assemble`: instancing the placements into one canopy (:func:`assemble_model`) and the
  checks on nesting and spacing;
- :mod:`.kernels`: the numba kernels (template positions, rest values, prediction, carry).
"""
from __future__ import annotations

from inflo.formats.fcc import CanopyParams
from inflo.formats.weights import read_weight_file

from .assemble import MAX_FLORETS as MAX_FLORETS
from .assemble import MAX_NEST_DEPTH as MAX_NEST_DEPTH
from .assemble import SPACING_LIMIT as SPACING_LIMIT
from .assemble import _nearest_present as _nearest_present
from .assemble import _rba_rows as _rba_rows
from .assemble import assemble_model
from .assemble import check_spacing as check_spacing
from .inputs import Inputs, RbaSequence, load_inputs
from .inputs import coincident_vertices as coincident_vertices
from .kernels import _rest_angles as _rest_angles
from .kernels import _rest_lengths as _rest_lengths
from .kernels import carry as carry
from .kernels import predict as predict
from .kernels import rest_values as rest_values
from .kernels import template_positions as template_positions
from .system import OBSTACLE as OBSTACLE
from .system import Floret, Model, Schedule, State, Template
from .system import Level as Level

__all__ = ["Template", "Floret", "Model", "Schedule", "State", "RbaSequence", "Inputs", "build_model",
           "load_inputs", "assemble_model", "read_weight_file"]


def build_model(params: CanopyParams) -> Model:
    """Load every file ``params`` names and instance every placement (thesis 8 f):
    :func:`load_inputs`, then :func:`assemble_model`.

    Raises
    ------
    FormatError, InputError
        Unreadable or malformed inputs; an animation whose frames differ in topology (naming the
        first differing frame); an SCN id with no ``animation``/``obj`` entry; an RBA id that is
        not an ``rba:`` placement of its scene; an ``rba:`` placement without a ``rigid body
        animation`` entry for its scene; a scene without placements.
    """
    inputs = load_inputs(params)
    return assemble_model(params, inputs.scenes, inputs.templates, inputs.rbas)
