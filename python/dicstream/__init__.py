"""dicstream from Python: the workspace's own correlator and identifier on numpy arrays.

- ``correlate(reference, deformed, ...)``: one displacement and strain field between two
  images (2-D arrays: uint8, uint16, or float grey levels in [0, 1]), as ``dicstream correlate``
  measures it; the GIL is released while it runs.
- ``identify(uniaxial=..., ...)``: the ranked fits of hyperelastic models to stretch-stress
  data, as ``dicstream identify --json`` reports them.
- ``read_results(path)``: a run's results folder (``summary.json``, ``identification.json``,
  ``frames.csv``, the ``fields/`` CSV files) as dicts and numpy arrays.
- ``read_image(path)``: a PNG, TIFF or BMP file as a uint16 array, by the CLI's reader.
- ``subscribe(service, instance=None, timeout=None)``: a live service's samples (``frames``,
  ``fields``, ``rig/state``, ``identification``); a frame's ``pixels`` and a field's ``nodes``
  are numpy views of the shared memory (no copy), the header's fields are attributes.
- ``layouts()``: the numpy dtypes of the shared-memory layouts, built from the Rust ones;
  ``NODE_STATUS`` and ``STRAIN_MEASURES``: their codes by name (a node's ``status``, a
  field's ``strain_measure``).

Bad input raises ``ValueError`` with the library's message.
"""

import csv
import json
import os

import numpy as np

from . import _dicstream
from ._dicstream import LAYOUT_VERSION, NODE_STATUS, STRAIN_MEASURES, layouts, read_image

__all__ = [
    "correlate", "identify", "read_results", "read_image", "subscribe", "layouts",
    "LAYOUT_VERSION", "NODE_STATUS", "STRAIN_MEASURES",
]


def subscribe(service, instance=None, timeout=None):
    """An iterator of the live samples of ``service`` ("frames", "fields", "rig/state",
    "identification") of ``instance`` (None: the default instance, ``dicstream_$USER``, as the
    CLI's). Each ``next()`` waits at most ``timeout`` seconds (None: until a sample comes) and
    then raises ``TimeoutError``; a sample of another layout version raises ``ValueError``.

    A sample has ``header`` (a 0-d numpy structured array) and the header's fields as
    attributes (``frame_id``, ``mesh_cols``, ``u_mean_px``, ...); a frame has ``pixels``
    (uint16, (height_px, width_px)), a field ``nodes`` (structured: ``x_px``, ``y_px``,
    ``u_px``, ``v_px``, ``exx``, ``eyy``, ``exy``, ``score``, ``iterations``, ``status``,
    ``du_dx``..``dv_dy``; (mesh_rows, mesh_cols)). Both are read-only views of the iceoryx2
    sample's shared memory: no copy is made, and the sample goes back to the publisher when
    the sample object and every view of it are gone. A subscriber holds at most
    ``max_borrowed`` samples at once: keep copies (``nodes.copy()``), not views, of samples
    you keep longer. A rig state or an identification report is a copied value.
    """
    return _dicstream.subscribe(service, instance=instance, timeout=timeout)


def correlate(reference, deformed, **settings):
    """The field between ``reference`` and ``deformed`` (2-D numpy arrays of one shape).

    Keyword settings, with the names and defaults of ``dicstream correlate`` (None: the
    default): ``method`` ("correli", "icgn1", "icgn2", "icgn"), ``zoi`` and ``step`` (px), ``roi``
    (None for the margin, "centred-pow2", "x,y,w,h" or a tuple), ``polygons`` (a list of
    "x,y x,y x,y ..."), ``mask`` (a path to a mask image), ``strain``, ``guess``,
    ``min_zncc``, ``gradient_correction``, ``threads``, ``max_iterations``, ``gauges`` (a list
    of "NAME=KIND:POINTS"), ``control_gauge``.

    Returns a dict: ``x``, ``y``, ``u``, ``v`` (px), ``exx``, ``eyy``, ``exy``, ``du_dx``,
    ``du_dy``, ``dv_dx``, ``dv_dy``, ``score``, ``iterations`` as (ny, nx) float arrays in the
    order of the field's CSV rows; ``status`` the (ny, nx) array of node status words;
    ``summary`` the frame's summary (the numbers of ``summary.json``'s frame entry);
    ``elapsed_ms`` the correlation's time (the frame's ``elapsed_ms`` there).
    """
    field = _dicstream.correlate(reference, deformed, **settings)
    field["status"] = np.array(field["status"]).reshape(field.pop("shape"))
    field["summary"] = json.loads(field["summary"])
    return field


def _columns(name, data):
    """A load case's (stretch, nominal stress in MPa) from an (n, 2) array, a pair of
    sequences or a data frame with ``stretch`` and ``nominal_stress_mpa`` columns."""
    if data is None:
        return None
    if hasattr(data, "columns"):
        missing = {"stretch", "nominal_stress_mpa"} - set(data.columns)
        if missing:
            raise ValueError(f"{name}: a data frame needs the columns stretch and nominal_stress_mpa")
        return (
            np.asarray(data["stretch"], dtype=float).tolist(),
            np.asarray(data["nominal_stress_mpa"], dtype=float).tolist(),
        )
    if isinstance(data, (tuple, list)) and len(data) == 2:
        stretch, stress = data
        return np.asarray(stretch, dtype=float).ravel().tolist(), np.asarray(stress, dtype=float).ravel().tolist()
    array = np.asarray(data, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(
            f"{name}: give an (n, 2) array of stretch and nominal stress (MPa), a pair of "
            f"sequences or a data frame, not shape {array.shape}"
        )
    return array[:, 0].tolist(), array[:, 1].tolist()


def _states(data):
    """General biaxial states: an (n, 4) array (λ1, λ2, P1, P2 in MPa) or a data frame with
    the columns of ``--biaxial-general``'s file."""
    if data is None:
        return []
    if hasattr(data, "columns"):
        names = ["lambda1", "lambda2", "nominal_stress1_mpa", "nominal_stress2_mpa"]
        if set(names) - set(data.columns):
            raise ValueError("biaxial_general: a data frame needs the columns " + ", ".join(names))
        data = np.column_stack([np.asarray(data[n], dtype=float) for n in names])
    array = np.asarray(data, dtype=float)
    if array.ndim != 2 or array.shape[1] != 4:
        raise ValueError(f"biaxial_general: give an (n, 4) array of λ1, λ2, P1, P2, not shape {array.shape}")
    return [tuple(row) for row in array.tolist()]


def identify(*, uniaxial=None, biaxial=None, pure_shear=None, biaxial_general=None, model=None,
             residual=None, max_fit_points=None, threads=None):
    """The ranked fits of ``model`` ("all" by default, or "NAME[,NAME...]") to the data.

    Each load case (uniaxial, biaxial: equibiaxial, pure_shear) is an (n, 2) array of stretch
    and nominal stress in MPa, a pair of sequences, or a data frame with columns ``stretch``
    and ``nominal_stress_mpa``; ``biaxial_general`` an (n, 4) array of λ1, λ2, P1, P2.

    Returns the dict of ``dicstream identify --json``: ``fits`` (ranked by AIC, each with
    ``model``, ``params``, ``stderr`` (σ), ``rms_mpa``, ``aic``, ``rank``, ``warning``...),
    ``failures``, ``paper_route`` and, above ``max_fit_points``, ``subsample``.
    """
    text = _dicstream.identify_json(
        uniaxial=_columns("uniaxial", uniaxial),
        biaxial=_columns("biaxial", biaxial),
        pure_shear=_columns("pure_shear", pure_shear),
        biaxial_general=_states(biaxial_general),
        model=model,
        residual=residual,
        max_fit_points=max_fit_points,
        threads=threads,
    )
    return json.loads(text)


def read_csv_columns(path):
    """A CSV file with a header as a dict of columns: float arrays, or string arrays for a
    column that is not all numbers (a node's status)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ValueError(f"{path}: empty file, no header")
    header, body = rows[0], rows[1:]
    columns = {}
    for j, name in enumerate(header):
        cells = [row[j] if j < len(row) else "" for row in body]
        try:
            columns[name] = np.array([float(c) if c != "" else np.nan for c in cells])
        except ValueError:
            columns[name] = np.array(cells)
    return columns


def read_results(path):
    """A run's results folder: ``summary`` and ``identification`` (the JSON files, None when
    absent), ``frames`` (``frames.csv``'s columns, None when absent) and ``fields``, a dict
    from each ``fields/*.csv`` file's name (without ``.csv``) to its columns (numpy arrays)."""
    if not os.path.isdir(path):
        raise ValueError(f"{path}: not a folder (a run's results folder was expected)")

    def json_file(name):
        p = os.path.join(path, name)
        if not os.path.exists(p):
            return None
        with open(p) as f:
            return json.load(f)

    frames = os.path.join(path, "frames.csv")
    fields_dir = os.path.join(path, "fields")
    fields = {}
    if os.path.isdir(fields_dir):
        for name in sorted(os.listdir(fields_dir)):
            if name.endswith(".csv"):
                fields[name[: -len(".csv")]] = read_csv_columns(os.path.join(fields_dir, name))
    return {
        "summary": json_file("summary.json"),
        "identification": json_file("identification.json"),
        "frames": read_csv_columns(frames) if os.path.exists(frames) else None,
        "fields": fields,
    }
