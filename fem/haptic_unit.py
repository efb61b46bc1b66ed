"""The haptic unit as an axisymmetric model: motor, flexible PCB, silicone rings and pogo pins.

The unit is described by the scene's dataclasses (``fem.scene.Unit`` and its parts), whose SI
views this module uses directly. Modelling assumptions (each a choice Guo et al. 2025 leave
open):

* **Motor.** The coin ERM housing is a solid cylinder of an effectively rigid material whose
  density spreads the motor's mass over its volume. The unbalance force F = m e omega^2 acts on
  the housing through the shaft, at the rotor plane on the axis. A force rotating parallel to
  the skin, Re{F e^{i omega t}(e_x - i e_y)}, is one Fourier n = 1 load: one complex solve of a
  horizontal force gives the whole steady field, and the amplitude at a point does not depend on
  theta. Its height above the contact plane carries the overturning moment F h.
* **Orientation.** "forward" keeps the motor as bought, base face towards the board, so the rotor
  plane sits ``rotor_height`` above the motor's lower face; "reverse" flips it, putting the rotor
  at ``height - rotor_height``. Both faces are taken as flat and fully bonded.
* **Board.** The flexible PCB is a thin disc under the motor, bonded to it.
* **Glued attachment.** The board (or the motor, without a board) is bonded to the skin over its
  footprint: nodes are shared.
* **Pogo pins.** N pins at radius R_p, each a spring k along its axis between the board and a
  frictionless tip on the skin. Frictionless contact passes no tangential force, so each pin is
  a vertical spring between the mean vertical displacement of the board's underside and of the
  skin over the tip footprint. The N pins are smeared into a ring: this keeps the total vertical
  stiffness N k (n = 0) and, for N >= 3 pins evenly spaced, the rocking stiffness N k R_p^2 / 2
  (n = 1) exactly; harmonics n = N, 2N, ... of the discrete pins are left out. Under the board
  between the pins is air. Contact is assumed maintained (the preload k x travel of each pin
  exceeds the dynamic pin force; ``preload`` checks it).
* **Encapsulation.** Each ring is a hollow cylinder, ``ring_thickness`` wide, from the skin to
  the top of the motor, bonded to its neighbours and to the skin. The paper ties the rings to
  each other and to the skin only; how the inner ring meets the motor is ``ring_contact``:
  "frictionless" (default) a snug fit that passes normal pressure but no shear, modelled by
  tying the radial displacement across a 0.05 mm slit over the core's height; "bonded" cast
  around the motor (shared nodes); "none" no interaction. With "none" and pogo pins nothing
  but its inertia holds the unit sideways: a transient drifts, a static solve is singular.
* **Center and edge.** The center amplitude is the unit's own vibration where it meets the skin:
  the displacement on the axis of its skin-side face (the skin under it when glued, the
  board's underside on pogo pins, where the skin on the axis is untouched). The edge is the
  unit's outer radius (the outermost ring, or the motor/board without rings); the edge
  amplitude is the skin-surface amplitude there, and the profile runs outwards from it.
  Normalized edge = edge / center.

All quantities SI (m, kg, N, Pa) unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .assembly import UZ
from .domain import Block, Domain
from .elements import dofs_per_node
from .loads import face_integrals
from .scene import Pogo, Unit


@dataclass(frozen=True)
class PinRing:
    """Smeared pogo pins: a vertical spring ring between two faces.

    Attributes:
        radius: pin axis radius (m).
        half_width: half the tip footprint (m).
        z_board: depth of the board's underside (m, negative: above the skin).
        stiffness: total stiffness N k (N/m) of all pins (mode 0 sees all of it, mode 1 half).
    """

    radius: float
    half_width: float
    z_board: float
    stiffness: float

    def mode_stiffness(self, mode: int) -> float:
        """Stiffness of the ring in Fourier mode n: c_n N k / (2 pi)."""
        return self.stiffness * (1.0 if mode == 0 else 0.5)


@dataclass(frozen=True)
class UnitLayout:
    """What the unit adds to a domain.

    Attributes:
        blocks: rectangles to paint above the skin (motor, board, rings).
        r_breaks, z_breaks: extra cell lines (m).
        rotor_z: depth of the rotor plane on the axis (m, negative).
        center_z: depth of the motor's center on the axis (m).
        contact_z: depth of the unit's skin-side face (m): 0 when glued, the board's underside
            on pogo pins. Its center is the unit's "center amplitude".
        pins: the smeared pogo pins, or None when glued.
        edge: the unit's outer radius (m).
        contact_ties: (r_core, r_ring, z_top, z_bottom) of a frictionless ring contact: the
            radial displacement is tied across the slit over that height; None otherwise.
    """

    blocks: tuple[Block, ...]
    r_breaks: tuple[float, ...]
    z_breaks: tuple[float, ...]
    rotor_z: float
    center_z: float
    contact_z: float
    pins: PinRing | None
    edge: float
    contact_ties: tuple[float, float, float, float] | None = None


def layout(unit: Unit, encapsulation: bool = True, unit_mass: bool = True,
           rocking: bool = True, hysteretic: bool = True) -> UnitLayout:
    """Place the unit's parts above the skin (z = 0, z positive into the tissue).

    Args:
        encapsulation: mesh the rings (off: the bare core; the nominal edge stays).
        unit_mass: give the motor and board their mass (off: massless housing).
        rocking: apply the unbalance at the rotor plane (off: at the motor's lower face, i.e.
            without the overturning moment).
        hysteretic: keep the rings' loss factors (off: purely elastic rings).
    """
    m, board = unit.motor, unit.board
    pogo = unit.attachment == "pogo"
    z_board_bottom = -unit.pogo.length_m if pogo else -0.0
    z_motor_bottom = z_board_bottom - board.thickness_m
    z_motor_top = z_motor_bottom - m.height_m
    rotor_z = z_motor_bottom - unit.rotor_above_base_m if rocking else z_motor_bottom

    blocks = [Block(0.0, m.radius_m, z_motor_top, z_motor_bottom, m.solid(unit_mass))]
    if board.present:
        blocks.append(Block(0.0, board.radius_m, z_motor_bottom, z_board_bottom,
                            board.board_solid(unit_mass)))
    r_in = unit.ring_start_m
    if encapsulation:
        for ring, (r0, r1) in zip(unit.encapsulation, unit.ring_radii_m, strict=True):
            blocks.append(Block(r0, r1, z_motor_top, 0.0, ring.solid(hysteretic)))

    r_breaks = [m.radius_m, unit.core_radius_m, r_in, unit.outer_radius_m]
    pins = None
    if pogo:
        p = unit.pogo
        half = 0.5 * p.tip_diameter_m
        r_breaks += [p.radius_m - half, p.radius_m + half]
        pins = PinRing(p.radius_m, half, z_board_bottom, p.total_stiffness_N_m)
    center_z = 0.5 * (z_motor_top + z_motor_bottom)
    z_breaks = (z_motor_top, z_motor_bottom, z_board_bottom, rotor_z, center_z)
    contact_z = z_board_bottom if board.present else z_motor_bottom
    ties = None
    if encapsulation and unit.encapsulation and unit.ring_contact == "frictionless":
        ties = (unit.core_radius_m, r_in, z_motor_top, contact_z)
    return UnitLayout(tuple(blocks), tuple(r_breaks), tuple(sorted(set(z_breaks))), rotor_z,
                      center_z, contact_z, pins, unit.outer_radius_m, ties)


def pin_compression(domain: Domain, mode: int, pins: PinRing) -> tuple[NDArray, NDArray]:
    """The pin compression as a linear functional b . u[dofs]: the mean U_z over the board-side
    footprint minus that over the skin-side footprint (m, amplitude of the mode)."""
    ndpn = dofs_per_node(mode)
    r0, r1 = pins.radius - pins.half_width, pins.radius + pins.half_width
    board_nodes, board_w = _mean_weights(*face_integrals(domain, pins.z_board, r0, r1, "above"))
    skin_nodes, skin_w = _mean_weights(*face_integrals(domain, 0.0, r0, r1, "below"))
    dofs = np.concatenate([board_nodes, skin_nodes]) * ndpn + UZ
    return dofs, np.concatenate([board_w, -skin_w])


def pin_spring(domain: Domain, mode: int, pins: PinRing) -> tuple[NDArray, NDArray]:
    """The smeared pins as one rank-1 element k_n b b^T (``pin_compression`` gives b).

    Returns (dofs (1, m), matrix (1, m, m)) for ``assemble_matrix``.
    """
    dofs, b = pin_compression(domain, mode, pins)
    return dofs[None, :], pins.mode_stiffness(mode) * np.outer(b, b)[None]


def _mean_weights(nodes: NDArray, weights: NDArray) -> tuple[NDArray, NDArray]:
    """Unique nodes and weights that average a field over a face (weights sum to 1)."""
    if nodes.size == 0:
        raise ValueError("pin footprint has no mesh face: check pogo radius and tip diameter")
    uniq, inv = np.unique(nodes.ravel(), return_inverse=True)
    w = np.bincount(inv, weights.ravel())
    return uniq, w / w.sum()


def pin_contact_check(domain: Domain, mode: int, pins: PinRing, pogo: Pogo,
                      u_full: NDArray) -> dict:
    """Check the linear pogo model: contact holds while the dynamic force of the most loaded
    pin, k |compression amplitude| (N), stays below its preload k x travel (N)."""
    dofs, b = pin_compression(domain, mode, pins)
    force = pogo.stiffness_N_m * float(np.abs(b @ u_full[dofs]))
    preload = pogo.preload_N
    return {"preload_per_pin_N": preload, "dynamic_pin_force_N": force,
            "contact_maintained": force < preload}
