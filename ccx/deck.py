"""The CalculiX input decks, as text (pure: arrays in, strings out).

Decks are in millimetres, newtons and megapascals (CalculiX has no units; this
is the usual consistent set). Metres would fail on fine meshes: CalculiX
refuses an element whose Jacobian determinant is below 1e-20 in the deck's
units, an absolute threshold that the small elements next to the axis of a
fine mesh cross in metres ("nonpositive jacobian"; docs/performance.md,
"Measurements behind the code", ``ccx/deck.py``); in millimetres it lies 1e9
lower. Every number fits CalculiX's
20 characters per field (longer fields are refused).

Every deck reads the sphere from ``sphere.inp`` (``*INCLUDE``): nodes, CAX6
elements, node sets, material, the axis condition u_r = 0. Node i + 1 is
contact node i (:mod:`ccx.model`). Axisymmetric models are expanded by
CalculiX into 2° wedges: a ``*CLOAD`` of a static step is the force on the
whole ring and reaction forces are printed per wedge (×180 for the ring); a
``*GREEN`` step applies a unit force to the wedge, i.e. 180 N on the ring.
"""

from __future__ import annotations

import numpy as np

#: millimetres per metre (lengths in the decks are in mm)
MM = 1e3
#: megapascals per pascal
MPA = 1e-6
#: ring force over the force CalculiX prints (or applies, in *GREEN) per 2° wedge
WEDGES = 180.0
#: the included model file
MODEL_FILE = "sphere.inp"
#: yield stress [MPa] of the never-yielding plastic law that makes a step nonlinear, so that
#: CalculiX iterates its gap elements (a purely linear step ignores them, silently)
NEVER_YIELD = 1e20
#: CalculiX reads at most this many characters of a field
FIELD_WIDTH = 20


def number(x: float) -> str:
    """``x`` in at most 20 characters, with as many significant digits as fit."""
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"cannot write {x!r} into a CalculiX deck")
    if x == 0.0:
        return "0."
    for digits in range(16, 0, -1):
        text = f"{x:.{digits}e}"
        if len(text) <= FIELD_WIDTH:
            return text
    raise ValueError(f"{x!r} does not fit {FIELD_WIDTH} characters")


def _id_lines(ids, per_line=10) -> str:
    ids = np.asarray(ids, np.int64) + 1
    return "".join(",".join(str(i) for i in ids[k:k + per_line]) + "\n"
                   for k in range(0, len(ids), per_line))


def model(sphere, youngs_modulus: float, poisson_ratio: float, *, nonlinear: bool = False,
          title: str = "") -> str:
    """``sphere.inp``: the sphere's nodes, CAX6 elements, sets and material.

    Sets: CONTACT (the contact arc, by r), LOADED (the contact nodes off the
    axis), TOP, AXIS; element set SPHERE. ``nonlinear`` adds a plastic law
    that never yields (:data:`NEVER_YIELD`) so that steps with gap elements
    iterate; the response stays linear elastic.
    """
    out = [f"** {title}\n" if title else "",
           "** the sphere of wearcheck's FEM mesh (CAX6); units mm, N, MPa\n*NODE,NSET=NALL\n"]
    out += [f"{i + 1},{number(r * MM)},{number(z * MM)}\n"
            for i, (r, z) in enumerate(sphere.points)]
    out.append("*ELEMENT,TYPE=CAX6,ELSET=SPHERE\n")
    out += [f"{e + 1}," + ",".join(str(v + 1) for v in nodes) + "\n"
            for e, nodes in enumerate(sphere.elements)]
    for name, ids in (("CONTACT", sphere.contact), ("LOADED", sphere.contact[1:]),
                      ("TOP", sphere.top), ("AXIS", sphere.axis)):
        out.append(f"*NSET,NSET={name}\n" + _id_lines(ids))
    out.append(f"*MATERIAL,NAME=SPHERE\n*ELASTIC\n{number(youngs_modulus * MPA)},"
               f"{number(poisson_ratio)}\n")
    if nonlinear:
        out.append(f"*PLASTIC\n{number(NEVER_YIELD)},0.\n")
    out.append("*SOLID SECTION,ELSET=SPHERE,MATERIAL=SPHERE\n*BOUNDARY\nAXIS,1,1\n")
    return "".join(out)


def compliance(title: str = "") -> str:
    """The deck of the contact nodes' compliance: one Green function per loaded node.

    The top face is clamped; ``*GREEN`` factorises the stiffness once and
    solves for a unit axial force at each node of LOADED (one linear load
    case each); the axial displacements of LOADED are printed per case.
    """
    return (f"** {title}\n" if title else "") + (
        "** compliance of the contact nodes: one Green function (unit axial force on the\n"
        "** 2-degree wedge, 180 N on the ring) per node of LOADED; run: ccx -i compliance\n"
        f"*INCLUDE,INPUT={MODEL_FILE}\n"
        "*BOUNDARY\nTOP,1,2\n"
        "*STEP\n*GREEN\n*CLOAD\nLOADED,2,1.\n"
        "*NODE PRINT,NSET=LOADED\nU\n*END STEP\n")


def recovery(sphere, stages, title: str = "") -> str:
    """The deck that recovers the fields at the stages from the contact forces.

    ``stages``: (depth [m], contact forces (Nc,) [N] on the ring, upward) per
    stage; one static step each, the top face clamped radially and lowered by
    the depth, the forces applied to the contact nodes. Writes U and S to the
    .frd file and the contact nodes' U to the .dat file.
    """
    out = [f"** {title}\n" if title else "",
           "** the fields at the stages: the contact forces of wearcheck's solution applied\n"
           "** to the sphere whose top face is lowered by the depth; run: ccx -i recovery\n"
           f"*INCLUDE,INPUT={MODEL_FILE}\n*BOUNDARY\nTOP,1,1\n"]
    for k, (depth, forces) in enumerate(stages):
        loaded = np.flatnonzero(np.asarray(forces) > 0)
        out.append(f"** stage {k + 1}\n*STEP\n*STATIC\n*BOUNDARY,OP=NEW\nAXIS,1,1\nTOP,1,1\n"
                   f"TOP,2,2,{number(-depth * MM)}\n*CLOAD,OP=NEW\n")
        out += [f"{sphere.contact[i] + 1},2,{number(forces[i])}\n" for i in loaded]
        out.append("*NODE FILE\nU\n*EL FILE\nS\n*NODE PRINT,NSET=CONTACT\nU\n*END STEP\n")
    return "".join(out)


def gap_step(sphere, clearance, *, control: str, value: float, stiffness: float,
             tension: float, depth_guess: float | None = None, fields: bool = False,
             iterations: int = 200, title: str = "") -> str:
    """One contact solve against the rigid plane with a gap element per contact node.

    Parameters
    ----------
    clearance : (Nc,) gap of each contact node to the plane before loading
        [m] (the initial gap plus the wear); the node on the axis has no gap
        element (its area is zero, as in the FEM) and its entry is unused.
    control, value : "depth" (the top face lowered by ``value`` [m]) or
        "force" (the top face kept flat by equations, ``value`` [N] pushing it).
    stiffness : gap stiffness [N/m] on the wedge; tension : the gap's force at
        infinite opening [N] on the wedge (CalculiX's default, 1e-3, would
        pull every open gap; see docs/ccx.md).
    depth_guess : force control: a first step lowers the top face by this
        depth [m] (the last known depth); the force step starts from its
        solution. Started from nothing, the sphere hangs free until a gap
        closes and Newton's method cuts back again and again (docs/performance.md,
        "Measurements behind the code", ``ccx/deck.py``).
    fields : also write U and S to the .frd file.
    iterations : most Newton iterations of the increment before CalculiX
        cuts it back (its default, 16, was enough on the meshes tried; raised
        for meshes whose contact edge moves by a node or two per iteration;
        docs/performance.md, "Measurements behind the code", ``ccx/deck.py``).

    Ground node Np + i sits on the plane under contact node i (i >= 1); gap
    element Ne + i joins them with direction -z: it closes when the contact
    node has come down by its clearance. The results are printed in the last
    step.
    """
    if control not in ("depth", "force"):
        raise ValueError(f"control {control!r}: must be 'depth' or 'force'")
    pts = sphere.points
    n_points, n_elements = len(pts), len(sphere.elements)
    nodes = sphere.contact[1:]
    ground = n_points + 1 + np.arange(len(nodes))
    c = np.asarray(clearance, float)[1:]
    out = [f"** {title}\n" if title else "",
           "** one contact solve: gap elements (GAPUNI) from the contact nodes to fixed nodes\n"
           "** on the rigid plane, clearance = initial gap + wear; run: ccx -i <this file>\n"
           f"*INCLUDE,INPUT={MODEL_FILE}\n*NODE,NSET=GROUND\n"]
    out += [f"{g},{number(pts[i, 0] * MM)},{number((pts[i, 1] - ci) * MM)}\n"
            for g, i, ci in zip(ground, nodes, c)]
    for e, (g, i, ci) in enumerate(zip(ground, nodes, c)):
        name = f"GAP{i + 1}"
        out.append(f"*ELEMENT,TYPE=GAPUNI,ELSET={name}\n{n_elements + e + 1},{i + 1},{g}\n"
                   f"*GAP,ELSET={name}\n{number(ci * MM)},0.,-1.,0.,,"
                   f"{number(stiffness / MM)},{number(tension)}\n")
    top = np.asarray(sphere.top) + 1
    supports = "GROUND,1,3\nAXIS,1,1\nTOP,1,1\n"
    out.append("*BOUNDARY\n" + supports)
    controls = (f"*CONTROLS,PARAMETERS=TIME INCREMENTATION\n{iterations},{iterations},"
                f"{iterations},{iterations},{iterations},4,,20\n")
    if control == "depth":
        out.append(f"*STEP,INC=100\n*STATIC\n{controls}*BOUNDARY\n"
                   f"TOP,2,2,{number(-value * MM)}\n")
    else:
        # the top face stays flat: every top node moves axially with the first
        out.append("*EQUATION\n" + "".join(f"2\n{t},2,1.,{top[0]},2,-1.\n" for t in top[1:])
                   + f"*NSET,NSET=TOPREF\n{top[0]}\n"
                   f"** first the last known depth, then the force from there\n"
                   f"*STEP,INC=100\n*STATIC\n{controls}*BOUNDARY\n"
                   f"TOPREF,2,2,{number(-depth_guess * MM)}\n*END STEP\n"
                   f"*STEP,INC=100\n*STATIC\n{controls}*BOUNDARY,OP=NEW\n{supports}"
                   f"*CLOAD\nTOPREF,2,{number(-value)}\n*NODE PRINT,NSET=TOPREF\nU\n")
    out.append("*NODE PRINT,NSET=CONTACT\nU\n*NODE PRINT,NSET=GROUND\nRF\n"
               "*NODE PRINT,NSET=TOP,TOTALS=ONLY\nRF\n")
    if fields:
        out.append("*NODE FILE\nU\n*EL FILE\nS\n")
    out.append("*END STEP\n")
    return "".join(out)
