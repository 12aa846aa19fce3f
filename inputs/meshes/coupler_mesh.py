#!/usr/bin/env python3
"""Write the five-body coupler (0.1 x 0.4 x 0.1 m along y, lower corner
(0.15, 0, -0.05)) as an flexmbs mesh file of NX x NY x NZ hex8 elements,
with the stiff tip regions of inputs/five_body.nml kept at 0.1 m whatever
the mesh: element sets 'tip_a' (y < 0.1), 'tip_b' (y > 0.3) and 'body'
(the rest), node sets 'ymin' and 'ymax' (the faces the joints attach to).

    python3 coupler_mesh.py NX NY NZ > coupler_NXxNYxNZ.mesh

NY must be a multiple of 4 so that element layers meet y = 0.1 and 0.3.
"""
import sys

ORIGIN = (0.15, 0.0, -0.05)
LENGTHS = (0.1, 0.4, 0.1)
TIP = 0.1  # m, thickness of each stiff tip region


def main():
    nx, ny, nz = (int(a) for a in sys.argv[1:4])
    if ny % 4:
        sys.exit("coupler_mesh.py: NY must be a multiple of 4")
    px, py, pz = nx + 1, ny + 1, nz + 1

    def node(i, j, k):  # 0-based grid indices -> 1-based node number
        return 1 + i + px * (j + py * k)

    out = [f"# The five-body coupler, {nx} x {ny} x {nz} hex8, written by "
           f"coupler_mesh.py {nx} {ny} {nz}:",
           "# 0.1 x 0.4 x 0.1 m along y; stiff tips 'tip_a' (y < 0.1) and 'tip_b'",
           "# (y > 0.3), the rest 'body'; the faces 'ymin' and 'ymax' as node sets.",
           "flexmbs-mesh 1", "", f"nodes {px * py * pz}"]
    for k in range(pz):
        for j in range(py):
            for i in range(px):
                x = [ORIGIN[d] + LENGTHS[d] * (i, j, k)[d] / (nx, ny, nz)[d] for d in range(3)]
                out.append(f"{node(i, j, k)} " + " ".join(f"{c:.15g}" for c in x))
    out += ["", f"elements hex8 {nx * ny * nz}"]
    sets = {"tip_a": [], "tip_b": [], "body": []}
    e = 0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                e += 1
                conn = [node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k),
                        node(i, j + 1, k), node(i, j, k + 1), node(i + 1, j, k + 1),
                        node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)]
                out.append(f"{e} " + " ".join(map(str, conn)))
                yc = LENGTHS[1] * (j + 0.5) / ny
                name = "tip_a" if yc < TIP else "tip_b" if yc > LENGTHS[1] - TIP else "body"
                sets[name].append(e)
    out.append("")
    for name, j in (("ymin", 0), ("ymax", ny)):
        nodes = [node(i, j, k) for k in range(pz) for i in range(px)]
        out.append(f"node_set {name} {len(nodes)}")
        out += [" ".join(map(str, nodes[s:s + 12])) for s in range(0, len(nodes), 12)]
    for name, elems in sets.items():
        out.append(f"element_set {name} {len(elems)}")
        out += [" ".join(map(str, elems[s:s + 12])) for s in range(0, len(elems), 12)]
    print("\n".join(out))


if __name__ == "__main__":
    main()
