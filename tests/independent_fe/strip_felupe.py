"""An independent finite-element check of dicstream's membrane (tests/independent_fe.rs).

The clamped uniaxial strip (length x width x thickness, mm) as a 3D nearly incompressible
solid in felupe (https://github.com/adtzlr/felupe): trilinear hexahedra, one eighth of the
strip by symmetry (planes x = 0, y = 0, z = 0), SolidBodyNearlyIncompressible with a bulk
modulus 5000 times the initial shear modulus. The grip at x = length/2 holds y and moves x,
and leaves the thickness free, as the membrane's clamp (a line of in-plane displacement) does.

The law is the paper's (Lambert-Diani-Rey) truncated after the linear term, whose energy has a
closed form: dW/dI1 = exp(a0 + a1 (I1 - 3)), dW/dI2 = exp(b0 + b1 (I2 - 3)), so
W = exp(a0) (exp(a1 (I1 - 3)) - 1) / a1 + exp(b0) (exp(b1 (I2 - 3)) - 1) / b1 (a1, b1 != 0),
on the isochoric invariants (the material is incompressible).

Usage: strip_felupe.py a0 a1 b0 b1 length width thickness stretch nx ny nz
Prints one JSON object: the grip's axial force (N), the elements, the seconds it took.
"""
import json
import sys
import time

import felupe as fem
import felupe.constitution.tensortrax as mat
import tensortrax.math as tm


def ldr_linear(C, a0, a1, b0, b1):
    J3 = tm.linalg.det(C) ** (-1 / 3)
    I1 = J3 * tm.trace(C)
    I2 = (I1**2 - J3**2 * tm.trace(C @ C)) / 2
    w1 = tm.exp(a0) * (tm.exp(a1 * (I1 - 3)) - 1) / a1
    w2 = tm.exp(b0) * (tm.exp(b1 * (I2 - 3)) - 1) / b1
    return w1 + w2


def main():
    a0, a1, b0, b1 = (float(v) for v in sys.argv[1:5])
    length, width, thickness, stretch = (float(v) for v in sys.argv[5:9])
    nx, ny, nz = (int(v) for v in sys.argv[9:12])
    half = (length / 2, width / 2, thickness / 2)
    mesh = fem.Cube(a=(0, 0, 0), b=half, n=(nx + 1, ny + 1, nz + 1))
    region = fem.RegionHexahedron(mesh)
    field = fem.FieldContainer([fem.Field(region, dim=3)])
    u = field[0]
    move = (stretch - 1.0) * length / 2
    boundaries = {
        "sym-x": fem.Boundary(u, fx=0.0, skip=(0, 1, 1)),
        "sym-y": fem.Boundary(u, fy=0.0, skip=(1, 0, 1)),
        "sym-z": fem.Boundary(u, fz=0.0, skip=(1, 1, 0)),
        "grip-y": fem.Boundary(u, fx=half[0], skip=(1, 0, 1)),
        "move": fem.Boundary(u, fx=half[0], skip=(0, 1, 1), value=move),
    }
    # Initial shear modulus: 2 (dW/dI1 + dW/dI2) at rest.
    mu = 2 * (2.718281828459045**a0 + 2.718281828459045**b0)
    umat = mat.Hyperelastic(ldr_linear, a0=a0, a1=a1, b0=b0, b1=b1)
    solid = fem.SolidBodyNearlyIncompressible(umat, field, bulk=5000 * mu)
    ramp = fem.math.linsteps([0, move], num=int(20 * (stretch - 1.0)) + 5)
    step = fem.Step(items=[solid], ramp={boundaries["move"]: ramp}, boundaries=boundaries)
    start = time.time()
    job = fem.CharacteristicCurve(steps=[step], boundary=boundaries["move"])
    job.evaluate(tol=1e-8, verbose=0)
    # The reaction on the grip face of one eighth: the whole section is four such quarters.
    force_n = 4 * float(job.y[-1][0])
    print(json.dumps({
        "grip_force_n": force_n,
        "elements": int(mesh.ncells),
        "seconds": time.time() - start,
    }))


if __name__ == "__main__":
    main()
