"""``wearcheck mesh CASE.toml [--out FILE.msh]``: the FEM sphere mesh of a case."""

from __future__ import annotations

import sys
from ._common import (add_case_arguments, add_json_argument, case_notes, load_case,
                      print_json)
from wearcheck import meshes
from wearcheck.cases import reference
from wearcheck.outputs import check_output_file, write_file
from wearcheck.resources import check_memory


def add_parser(sub):
    p = sub.add_parser("mesh", help="generate (or fetch from the cache) the FEM mesh of a case",
                       description=__doc__)
    add_case_arguments(p)
    # a str, not a Path: Path drops a trailing "/", which says the user meant a directory
    p.add_argument("--out", default=None, metavar="FILE.msh",
                   help="also copy the gmsh .msh file here")
    add_json_argument(p, "the mesh's counts and sizes")
    return p


def main(args) -> int:
    # lazy (a): the FEM's module loads scikit-fem, the optional "fem" extra
    from wearcheck.fem.solver import mesh_parameters
    case = load_case(args)
    if args.out is not None:
        check_output_file(args.out, "mesh")  # before meshing
    check_memory(case, "fem")  # the mesh is the FEM's: refuse one it could never solve
    params = mesh_parameters(case)
    mesh = meshes.sphere_mesh(params)
    order = case.fem.element_order
    edges = params.contact_edges
    contact_nodes = edges * order + 1
    nodes = len(mesh.points)
    if order == 2:
        # every triangle edge carries a midside node: N_v + N_edges nodes
        n_edges = (3 * len(mesh.triangles) + sum(len(v) for k, v in mesh.lines.items())) // 2
        nodes += n_edges
    if args.out is not None:
        write_file(args.out, mesh.path, "mesh")
    case_notes(args, case)
    a0 = reference.scales(case)["a0"]
    file = args.out if args.out is not None else mesh.path
    if args.json:
        print_json(dict(vertices=len(mesh.points), triangles=len(mesh.triangles), order=order,
                        nodes=nodes, dofs=2 * nodes, contact_nodes=contact_nodes,
                        contact_radius=params.contact_radius,
                        contact_radius_over_a0=params.contact_radius / a0,
                        spacing=params.contact_radius / (edges * order), file=file,
                        cached=not mesh.generate_seconds))
    else:
        print(f"mesh: {len(mesh.points)} vertices, {len(mesh.triangles)} triangles; "
              f"order {order}: {nodes} nodes, {2 * nodes} DOFs; {contact_nodes} contact nodes "
              f"on 0 <= r <= {params.contact_radius:.4g} m ({params.contact_radius / a0:.3g} "
              f"a0, spacing {params.contact_radius / (edges * order):.3g} m)")
        print(f"file: {file}" + ("" if mesh.generate_seconds else " (from the cache)"))
    if not args.quiet and mesh.generate_seconds:
        print(f"gmsh: {mesh.generate_seconds:.3g} s", file=sys.stderr)
    return 0
