"""Correlate a DIC Challenge pair from Python and plot u (needs `pip install ./python`;
matplotlib optional).

    python examples/python/correlate_pair.py [REFERENCE DEFORMED] [--out u.png]

Without images: sample 5's reference and its image shifted by (0.1, 0.1) px, from testdata/.
"""

import argparse
from pathlib import Path

import numpy as np

import dicstream

SAMPLE5 = Path(__file__).resolve().parents[2] / "testdata" / "dic-challenge" / "sample5"

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("images", nargs="*", type=Path, help="reference and deformed image files")
parser.add_argument("--method", default="correli", help="correli, icgn1, icgn2 or icgn")
parser.add_argument("--out", type=Path, default=Path("u.png"), help="the figure of u (PNG)")
args = parser.parse_args()
if args.images and len(args.images) != 2:
    parser.error("give two images (reference, deformed) or none")
reference_path, deformed_path = args.images or (
    SAMPLE5 / "Sample5 Reference.tif",
    SAMPLE5 / "Sample5-001 X0.10 Y0.10 N2 C100 R20.tif",
)

reference = dicstream.read_image(reference_path)
deformed = dicstream.read_image(deformed_path)
field = dicstream.correlate(reference, deformed, method=args.method)
summary = field["summary"]
ok = field["status"] == "ok"
print(f"{summary['valid']} of {summary['nodes_in_region']} nodes valid; "
      f"median u {np.median(field['u'][ok]):+.4f} px, v {np.median(field['v'][ok]):+.4f} px")

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no figure (pip install matplotlib)")
    raise SystemExit(0)

u = np.where(ok, field["u"], np.nan)
figure, axes = plt.subplots(figsize=(6, 5))
axes.imshow(reference, cmap="gray")
x, y = field["x"], field["y"]
mesh = axes.pcolormesh(x, y, u, cmap="viridis", alpha=0.8, shading="nearest")
figure.colorbar(mesh, ax=axes, label="u (px)")
axes.set_title(f"u, {deformed_path.name}")
figure.savefig(args.out, dpi=120, bbox_inches="tight")
print(f"wrote {args.out}")
