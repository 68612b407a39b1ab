#!/usr/bin/python3
"""A large sample from a small one: the sample mirrored into nx x ny tiles, at rest under the same pressure.

  scripts/tile_sample.py IN.h5 OUT.h5 --tiles NX,NY

IN is a kergs sample compacted in the four walls of -box (it records them in /sample/box). Tile (i, j) is IN
reflected in x when i is odd and in y when j is odd, and shifted by i box widths and j box heights. Every grain that
touched a wall of IN then touches its own mirror image across the seam, at the same point and along the same normal.
By symmetry the two carry equal normal forces and no tangential force, which is what a frictionless wall gave them:
a frictionless compaction's sample at rest under p stays at rest under p, seams included, and OUT is ready for a test
without a second compaction (docs/biaxial.md, "10^6 disks"). Velocities, spins and orientations are reflected with
the grains. OUT records the box of the whole tiling, so a test reads it with -box_from_sample.

The contact forces IN records (/sample/contacts, the warm start of the test's first step) are mirrored with their
tiles: a grain's force on a wall becomes, across a seam, its force on its image, and stays a wall's on the tiling's
outer sides. The test then starts from the equilibrated force network, not from zero.

What it is not: a random sample of NX x NY times IN's size. Its grain-scale disorder repeats with a period of two
tiles, and the seams are mirror lines. OUT is written atomically (a temporary file in its directory, renamed); IN is
never written.
"""
import argparse
import math
import os
import sys
import tempfile

import h5py
import numpy as np

FORMAT = "kergs sample 1"
PER_GRAIN = {"x": 2, "v": 2, "rot": 1, "omega": 1, "radius": 1, "material": 1, "id": 1}  # docs/results.md, "Sample file"
PER_CONTACT = {"a_id": 1, "kind": 1, "b_id": 1, "force": 2}
BOX_SIDES = ("left", "bottom", "right", "top")
MIRROR_X = {"left": "right", "right": "left"}
MIRROR_Y = {"bottom": "top", "top": "bottom"}
# A compaction leaves its grains interpenetrating its walls by its solver's tolerance: at most 7.4e-7 m in the shipped
# samples (cases/compact_5k.h5). Grains may cross the box, and must reach each of its sides, within 1e-3 of the
# smallest radius (1e-5 m there): a seam the grains do not reach leaves them unsupported.
WALL_SLACK = 1e-3


def fail(message):
    sys.exit("tile_sample.py: " + message)


def parse_tiles(text):
    try:
        nx, ny = (int(word) for word in text.split(","))
    except ValueError:
        fail(f"--tiles {text!r}: expected two positive integers NX,NY")
    if nx < 1 or ny < 1 or nx * ny < 2:
        fail(f"--tiles {text!r}: expected NX,NY >= 1 with at least two tiles")
    return nx, ny


def read_sample(path):
    """The sample's datasets, its group's and root's attributes, and its box."""
    if os.path.isdir(path):
        fail(f"{path}: is a directory, not a sample file")
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    try:
        handle = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    with handle:
        kind = handle.attrs.get("kergs_format")
        if isinstance(kind, bytes):
            kind = kind.decode()
        if kind != FORMAT or not isinstance(handle.get("sample"), h5py.Group):
            fail(f"{path}: not a kergs sample (root attribute kergs_format is not '{FORMAT}')")
        group = handle["sample"]
        if not isinstance(group.get("box"), h5py.Dataset):
            fail(f"{path}: no /sample/box: tiling needs the box the sample was compacted in (-box)")
        missing = [name for name in PER_GRAIN if not isinstance(group.get(name), h5py.Dataset)]
        if missing:
            fail(f"{path}: /sample lacks the dataset(s) {', '.join(missing)}")
        data = {name: group[name][()] for name in PER_GRAIN}
        box = np.asarray(group["box"][()], dtype=float)
        return data, dict(group.attrs), dict(handle.attrs), box, read_contacts(path, group)


def read_contacts(path, group):
    """/sample/contacts, or None when the sample records no contact forces."""
    contacts = group.get("contacts")
    if contacts is None:
        return None
    if not isinstance(contacts, h5py.Group) or "walls" not in contacts.attrs:
        fail(f"{path}: /sample/contacts is not a group with the attribute walls")
    missing = [name for name in PER_CONTACT if not isinstance(contacts.get(name), h5py.Dataset)]
    if missing:
        fail(f"{path}: /sample/contacts lacks the dataset(s) {', '.join(missing)}")
    walls, count = contacts.attrs["walls"], np.asarray(contacts.attrs.get("ncontacts", -1))
    if not (isinstance(walls, (bytes, str)) and walls):
        fail(f"{path}: the attribute walls of /sample/contacts is not a string of wall names")
    walls = (walls.decode() if isinstance(walls, bytes) else walls).split(",")
    if len(set(walls)) != len(walls):
        fail(f"{path}: the attribute walls of /sample/contacts names a wall twice")
    data = {name: contacts[name][()] for name in PER_CONTACT}
    if any(data[name].dtype.kind not in "fiu" for name in PER_CONTACT):
        fail(f"{path}: /sample/contacts holds datasets that are not numbers")
    if count.shape != () or count.dtype.kind not in "iu" or int(count) != len(data["a_id"]):
        fail(f"{path}: the attribute ncontacts of /sample/contacts is not one integer equal to its {len(data['a_id'])} rows")
    return {"walls": walls, **data}


def check_rows(path, group, data, widths, n):
    """Each dataset of `widths` holds n rows of its width, all finite."""
    for name, width in widths.items():
        shape = (n, width) if width > 1 else (n,)
        if data[name].shape != shape:
            fail(f"{path}: {group}/{name} has shape {data[name].shape}, expected {shape}")
        if not np.all(np.isfinite(data[name])):
            fail(f"{path}: {group}/{name} holds NaN or infinite values")


def validate_contacts(path, contacts, ids):
    """Every contact of a grain of the sample with a grain of larger id or a box wall, with a finite force."""
    check_rows(path, "/sample/contacts", contacts, PER_CONTACT, len(contacts["a_id"]))
    kind, a, b = contacts["kind"], contacts["a_id"], contacts["b_id"]
    if not np.all((kind == 0) | (kind == 1)):
        fail(f"{path}: /sample/contacts/kind holds values other than 0 (grain) and 1 (wall)")
    grain = kind == 0
    if not (np.all(np.isin(a, ids)) and np.all(np.isin(b[grain], ids)) and np.all(b[grain] > a[grain])):
        fail(f"{path}: /sample/contacts names grains the sample does not hold, or a pair not by its smaller id first")
    if np.any(contacts["force"][:, 0] < 0):
        fail(f"{path}: /sample/contacts holds a negative normal force (contacts push)")
    keys = np.column_stack([a, kind, b])
    if len(np.unique(keys, axis=0)) != len(keys):
        fail(f"{path}: /sample/contacts gives a pair twice")
    walls = contacts["walls"]
    if not np.all((b[~grain] >= 0) & (b[~grain] < len(walls)) & (b[~grain] == np.round(b[~grain]))):
        fail(f"{path}: /sample/contacts/b_id names walls outside its attribute walls")
    sides = [name[4:] for name in walls]
    for index in np.unique(b[~grain]).astype(int):
        if not walls[index].startswith("box_") or sides[index] not in BOX_SIDES:
            fail(f"{path}: its contacts name the wall {walls[index]!r}, which is not one of the box's: only box walls can be mirrored")
    # A seam replaces a frictionless wall: a wall contact's tangential force has no mirror image (rounding aside).
    normal = np.abs(contacts["force"][:, 0]).max(initial=0.0)
    if np.any(np.abs(contacts["force"][~grain, 1]) > 1e-9 * normal):
        fail(f"{path}: its grains carry tangential forces on the box walls (a compaction with wall friction): "
             "a mirror tiling holds them with no tangential force and would not be in equilibrium")
    return sides


def validate(path, data, attrs, box):
    """Refuse what the tiling would turn into a broken sample: shapes, values, the box where the walls stood."""
    n = len(data["radius"]) if data["radius"].ndim == 1 else 0
    if n == 0:
        fail(f"{path}: /sample/radius is empty or not a list of radii")
    check_rows(path, "/sample", data, PER_GRAIN, n)
    if "ndisks" not in attrs or int(np.asarray(attrs["ndisks"]).ravel()[0]) != n:
        fail(f"{path}: the attribute ndisks does not match the {n} rows of /sample/radius")
    if len(np.unique(data["id"])) != n:
        fail(f"{path}: /sample/id holds repeated ids")
    if box.size != 4 or not np.all(np.isfinite(box)):
        fail(f"{path}: /sample/box {box.ravel().tolist()} is not x0, y0, x1, y1")
    box = box.reshape(4)
    if box[2] <= box[0] or box[3] <= box[1]:
        fail(f"{path}: /sample/box {box.tolist()} is not a box (x1 > x0, y1 > y0)")
    x, r = data["x"], data["radius"]
    gaps = np.array([(x[:, 0] - r).min() - box[0], (x[:, 1] - r).min() - box[1], box[2] - (x[:, 0] + r).max(),
                     box[3] - (x[:, 1] + r).max()])
    slack = WALL_SLACK * r.min()
    if np.any(np.abs(gaps) > slack):
        side = ("left", "bottom", "right", "top")[int(np.argmax(np.abs(gaps)))]
        fail(f"{path}: the grains stand {np.abs(gaps).max():.3g} m off the box's {side} side (more than {slack:.3g} m): "
             "the box is not where the compaction's walls stopped, and the seams would not touch")
    return box


def mirror_tile(data, box, i, j, id_offset):
    """Tile (i, j): the sample reflected in x when i is odd, in y when j is odd, then shifted."""
    size = box[2:] - box[:2]
    flip = np.array([-1.0 if i % 2 else 1.0, -1.0 if j % 2 else 1.0])
    local = data["x"] - box[:2]
    local = np.where(flip > 0, local, size - local)
    handedness = flip[0] * flip[1]  # a reflection reverses the sense of rotation, two restore it
    return {
        "x": box[:2] + np.array([i, j]) * size + local,
        "v": data["v"] * flip,
        "omega": data["omega"] * handedness,
        # an orientation angle theta becomes pi - theta in a reflection in x and -theta in one in y
        "rot": data["rot"] * handedness + (math.pi if flip[0] < 0 else 0.0),
        "radius": data["radius"],
        "material": data["material"],
        "id": data["id"] + id_offset,
    }


def tile(data, box, nx, ny):
    """The mirrored tiling, tile by tile (i fastest), and its box. Ids stay unique: each tile's are shifted past the
    previous tiles'."""
    stride = id_stride(data)
    tiles = [mirror_tile(data, box, i, j, (j * nx + i) * stride) for j in range(ny) for i in range(nx)]
    out = {name: np.concatenate([t[name] for t in tiles]).astype(data[name].dtype) for name in PER_GRAIN}
    size = box[2:] - box[:2]
    return out, np.concatenate([box[:2], box[:2] + np.array([nx, ny]) * size])


def id_stride(data):
    return int(np.max(data["id"])) + 1


def mirror_contacts(contacts, sides, stride, i, j, nx, ny):
    """Tile (i, j)'s contacts. In the contact frame (n from b to a, t = (-n_y, n_x)) a reflection keeps the normal force
    and reverses the tangential one. A wall contact on a side of the tiling stays one (the wall of that side); on a seam
    it becomes the contact of the grain with its image in the next tile, which carries the wall's normal force and,
    by the mirror symmetry, no tangential force. The seam's contact is written once, by the tile left of or below it."""
    offset = (j * nx + i) * stride
    handedness = (-1.0 if i % 2 else 1.0) * (-1.0 if j % 2 else 1.0)
    wall_index = {side: k for k, side in enumerate(sides)}
    border = {"left": i == 0, "right": i == nx - 1, "bottom": j == 0, "top": j == ny - 1}
    neighbour = {"right": stride, "top": nx * stride}  # id offset of the tile across that seam
    rows = [(a + offset, 0, b + offset, fn, handedness * ft)
            for a, kind, b, (fn, ft) in zip(contacts["a_id"], contacts["kind"], contacts["b_id"], contacts["force"]) if kind == 0]
    for a, kind, b, (fn, ft) in zip(contacts["a_id"], contacts["kind"], contacts["b_id"], contacts["force"]):
        if kind == 0:
            continue
        side = sides[int(b)]
        side = MIRROR_X.get(side, side) if i % 2 else side
        side = MIRROR_Y.get(side, side) if j % 2 else side
        if border[side]:
            rows.append((a + offset, 1, wall_index[side], fn, handedness * ft))
        elif side in neighbour:
            rows.append((a + offset, 0, a + offset + neighbour[side], fn, 0.0))
    table = np.array(rows, dtype=float).reshape(-1, 5)
    return {"a_id": table[:, 0], "kind": table[:, 1], "b_id": table[:, 2], "force": table[:, 3:5]}


def tile_contacts(contacts, sides, data, nx, ny):
    stride = id_stride(data)
    tiles = [mirror_contacts(contacts, sides, stride, i, j, nx, ny) for j in range(ny) for i in range(nx)]
    out = {name: np.concatenate([t[name] for t in tiles]).astype(float) for name in PER_CONTACT}
    out["walls"] = contacts["walls"]
    return out


def write_sample(path, root_attrs, attrs, data, box, contacts):
    """Into a temporary file of OUT's directory, renamed onto OUT once complete; removed on failure."""
    directory = os.path.dirname(os.path.abspath(path))
    descriptor, temporary = tempfile.mkstemp(prefix=".tile_sample.", suffix=".h5", dir=directory)
    os.close(descriptor)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(temporary, 0o666 & ~umask)  # mkstemp's 0600 would make OUT private, unlike every other file kergs writes
    try:
        with h5py.File(temporary, "w") as handle:
            for key, value in root_attrs.items():
                handle.attrs[key] = value
            group = handle.create_group("sample")
            for key, value in attrs.items():
                group.attrs[key] = value
            group.attrs["ndisks"] = np.asarray(len(data["radius"]), dtype=np.asarray(attrs["ndisks"]).dtype)
            for name, values in data.items():
                group.create_dataset(name, data=values)
            group.create_dataset("box", data=box.reshape(1, 4))
            if contacts is not None:
                forces = group.create_group("contacts")
                forces.attrs["ncontacts"] = np.asarray(len(contacts["a_id"]), dtype=np.asarray(attrs["ndisks"]).dtype)
                forces.attrs["walls"] = np.bytes_(",".join(contacts["walls"]))  # fixed length, as PETSc's viewer reads it
                for name in PER_CONTACT:
                    forces.create_dataset(name, data=contacts[name])
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def check_output(input_path, output_path):
    directory = os.path.dirname(os.path.abspath(output_path))
    if not os.path.isdir(directory):
        fail(f"{output_path}: its directory {directory} does not exist")
    if os.path.exists(output_path) and not os.path.isfile(output_path):
        fail(f"{output_path}: exists and is not a regular file")
    if os.path.exists(output_path) and os.path.samefile(input_path, output_path):
        fail(f"{output_path}: is the input; write the tiling elsewhere")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--tiles", required=True, help="NX,NY")
    args = parser.parse_args()
    nx, ny = parse_tiles(args.tiles)
    data, attrs, root_attrs, box, contacts = read_sample(args.input)
    box = validate(args.input, data, attrs, box)
    sides = validate_contacts(args.input, contacts, data["id"]) if contacts is not None else None
    check_output(args.input, args.output)
    tiled, tiled_box = tile(data, box, nx, ny)
    tiled_contacts = tile_contacts(contacts, sides, data, nx, ny) if contacts is not None else None
    write_sample(args.output, root_attrs, attrs, tiled, tiled_box, tiled_contacts)
    forces = f", {len(tiled_contacts['a_id'])} contact forces" if tiled_contacts is not None else ", no contact forces"
    print(f"tile_sample.py: {args.output}: {len(tiled['radius'])} disks ({nx} x {ny} mirrored tiles of {len(data['radius'])}){forces}, box "
          + ",".join(f"{b:.9g}" for b in tiled_box))


if __name__ == "__main__":
    main()
