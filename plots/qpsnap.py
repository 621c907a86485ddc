"""Reader and writer for contactbench ``.qpsnap`` v1 and v2 snapshots (numpy only; scipy optional).

Layout (DESIGN.md "Snapshot format"): 8-byte little-endian uint64 N, N bytes of UTF-8 JSON
header, then a data buffer of little-endian arrays at 8-byte aligned offsets, each with its
zlib CRC32. The checks are those of the C++ reader (problems/qpsnap.cpp) and errors name the
file and the field: ``QpsnapError("PATH: A.indices: column 7 out of range [0, 6) in row 3")``.

    snap = read_qpsnap("frame_0003.qpsnap")
    snap["n"], snap["m"], snap["meta"], snap["arrays"]["b"]
    A, J = matrices(snap)            # scipy.sparse.csr_matrix, needs scipy

    # min 1/2 x'Ax - b'x  subject to  Jx >= c, from numpy/scipy arrays (A symmetric):
    write_qpsnap("mine.qpsnap", A, b, J, c, x0=None, meta={"family": "mine"})

    # version 2, Coulomb friction (solvers/core/qp.hpp Friction): mu per contact row, T (2m x n) the two
    # tangent rows of contact i at rows 2i, 2i+1 (FCLIB's local frame, J's row i the normal),
    # optional cT (2m), h (time step) and v0 (n, needs h):
    write_qpsnap("fric.qpsnap", A, b, J, c, mu=mu, T=T, h=0.01, v0=v0)
    T = tangents(snap)               # scipy.sparse.csr_matrix or None
"""

import json
import zlib

import numpy as np

__all__ = ["QpsnapError", "read_qpsnap", "read_header", "matrices", "tangents", "content_hash", "write_qpsnap",
           "REQUIRED", "OPTIONAL", "VERSION2"]

REQUIRED = {
    "A.indptr": "int64", "A.indices": "int64", "A.data": "float64", "b": "float64", "x0": "float64",
    "J.indptr": "int64", "J.indices": "int64", "J.data": "float64", "c": "float64",
}
OPTIONAL = {
    "contact.kind": "int64", "contact.depth": "float64", "contact.vertex": "int64",
    "x_ref": "float64", "lambda_ref": "float64",
    # version 2: Coulomb friction
    "mu": "float64", "T.indptr": "int64", "T.indices": "int64", "T.data": "float64", "cT": "float64", "v0": "float64",
}
VERSION2 = ("mu", "T.indptr", "T.indices", "T.data", "cT", "v0")  # the arrays only version 2 may hold
_MAX_INT32 = 2147483647


class QpsnapError(ValueError):
    """A snapshot failed validation; the message names the file and the field."""


def _fail(path, field, problem):
    raise QpsnapError(f"{path}: {field}: {problem}" if field else f"{path}: {problem}")


def _is_uint(v):
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def _parse_header(path, raw, file_size):
    if file_size < 8:
        _fail(path, "header", f"file too short: {file_size} bytes, a .qpsnap starts with an 8-byte header length")
    n_header = int.from_bytes(raw[:8], "little")
    if n_header > file_size - 8:
        _fail(path, "header", f"header length {n_header} exceeds the file ({file_size - 8} bytes after the length field)")
    try:
        header = json.loads(bytes(raw[8:8 + n_header]).decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as e:
        _fail(path, "header", f"not valid UTF-8 JSON ({e})")
    if not isinstance(header, dict):
        _fail(path, "header", f"expected a JSON object, got {type(header).__name__}")
    if "format" not in header:
        _fail(path, "format", 'missing (expected "qpsnap")')
    if header["format"] != "qpsnap":
        _fail(path, "format", f'expected "qpsnap", got {json.dumps(header["format"])}')
    if "version" not in header:
        _fail(path, "version", "missing (expected 1 or 2)")
    if header["version"] not in (1, 2) or isinstance(header["version"], bool):
        _fail(path, "version",
              f"unsupported version {json.dumps(header['version'])} (this reader knows versions 1 and 2)")
    for key in ("n", "m"):
        if key not in header:
            _fail(path, key, "missing")
        if not _is_uint(header[key]):
            _fail(path, key, f"expected a non-negative integer, got {json.dumps(header[key])}")
        if header[key] > _MAX_INT32:
            _fail(path, key, f"too large: {header[key]} > 2147483647 (indices are 32-bit)")
    if not isinstance(header.get("arrays"), dict):
        _fail(path, "arrays", "missing or not an object")
    if "meta" in header and not isinstance(header["meta"], dict):
        _fail(path, "meta", f"expected an object, got {json.dumps(header['meta'])}")
    if "h" in header:
        if header["version"] == 1:
            _fail(path, "h", "a version 2 field in a version 1 snapshot")
        step = header["h"]
        if isinstance(step, bool) or not isinstance(step, (int, float)) or not (step > 0 and np.isfinite(step)):
            _fail(path, "h", f"expected a positive finite time step, got {json.dumps(step)}")
    return header, n_header


def read_header(path):
    """The JSON header only (validated as far as the header goes)."""
    with open(path, "rb") as f:
        head = f.read(8)
        f.seek(0, 2)
        size = f.tell()
        if len(head) == 8:
            n_header = int.from_bytes(head, "little")
            if n_header <= size - 8:
                f.seek(0)
                head = f.read(8 + n_header)
    return _parse_header(path, head, size)[0]


def _locate(path, name, dtype, entry, buf):
    if not isinstance(entry, dict):
        _fail(path, name, "expected an object {dtype, shape, offset, nbytes, crc32}")
    for key in ("dtype", "shape", "offset", "nbytes", "crc32"):
        if key not in entry:
            _fail(path, f"{name}.{key}", "missing")
    if entry["dtype"] != dtype:
        _fail(path, f"{name}.dtype", f'expected "{dtype}", got {json.dumps(entry["dtype"])}')
    shape = entry["shape"]
    if not isinstance(shape, list):
        _fail(path, f"{name}.shape", f"expected an array of integers, got {json.dumps(shape)}")
    count = 1
    for d in shape:
        if not _is_uint(d):
            _fail(path, f"{name}.shape", f"expected a non-negative integer, got {json.dumps(d)}")
        count *= d
    for key in ("offset", "nbytes", "crc32"):
        if not _is_uint(entry[key]):
            _fail(path, f"{name}.{key}", f"expected a non-negative integer, got {json.dumps(entry[key])}")
    offset, nbytes = entry["offset"], entry["nbytes"]
    if nbytes != count * 8:
        _fail(path, f"{name}.nbytes", f"{nbytes} does not match shape {json.dumps(shape)} (expected {count * 8})")
    if offset % 8:
        _fail(path, f"{name}.offset", f"{offset} is not 8-byte aligned")
    if offset > len(buf) or nbytes > len(buf) - offset:
        _fail(path, f"{name}.offset", f"bytes [{offset}, {offset + nbytes}) lie outside the data buffer of {len(buf)} bytes")
    view = buf[offset:offset + nbytes]
    crc = zlib.crc32(view) & 0xFFFFFFFF
    if crc != entry["crc32"]:
        _fail(path, f"{name}.crc32", f"mismatch: header says {entry['crc32']}, data has {crc}")
    arr = np.frombuffer(view, dtype="<i8" if dtype == "int64" else "<f8")
    return arr.reshape(shape) if len(shape) != 1 else arr


def _expect_shape(path, name, arr, shape, why):
    if list(arr.shape) != list(shape):
        _fail(path, f"{name}.shape", f"expected {list(shape)} ({why}), got {list(arr.shape)}")


def _check_csr(path, mat, indptr, indices, rows, cols):
    nnz = len(indices)
    if indptr[0] != 0:
        _fail(path, f"{mat}.indptr", f"must start at 0, starts at {indptr[0]}")
    steps = np.diff(indptr)
    bad = np.flatnonzero(steps < 0)
    if bad.size:
        r = int(bad[0])
        _fail(path, f"{mat}.indptr", f"decreases at row {r} ({indptr[r]} then {indptr[r + 1]})")
    if indptr[rows] != nnz:
        _fail(path, f"{mat}.indptr", f"ends at {indptr[rows]}, expected nnz = {nnz} (the length of {mat}.indices)")
    row_of = np.repeat(np.arange(rows), steps)
    out = np.flatnonzero((indices < 0) | (indices >= cols))
    if out.size:
        e = int(out[0])
        _fail(path, f"{mat}.indices", f"column {indices[e]} out of range [0, {cols}) in row {row_of[e]}")
    if nnz > 1:
        same_row = row_of[1:] == row_of[:-1]
        bad = np.flatnonzero(same_row & (indices[1:] <= indices[:-1]))
        if bad.size:
            e = int(bad[0]) + 1
            _fail(path, f"{mat}.indices",
                  f"columns not strictly increasing in row {row_of[e]} ({indices[e - 1]} then {indices[e]})")
    return row_of


def read_qpsnap(path):
    """Reads and validates a snapshot: {"n", "m", "meta", "header", "arrays": {name: ndarray}}.

    A.data is returned symmetrised exactly, ((A + A') / 2), as the C++ reader does; the arrays are
    read-only views of the file's bytes, except A.data.
    """
    path = str(path)
    with open(path, "rb") as f:
        raw = f.read()
    header, n_header = _parse_header(path, raw, len(raw))
    n, m = header["n"], header["m"]
    buf = memoryview(raw)[8 + n_header:]
    for name in header["arrays"]:
        if name not in REQUIRED and name not in OPTIONAL:
            _fail(path, f"arrays.{name}", "unknown array name")
        if header["version"] == 1 and name in VERSION2:
            _fail(path, f"arrays.{name}", "a version 2 array in a version 1 snapshot")
    a = {}
    for name, dtype in list(REQUIRED.items()) + list(OPTIONAL.items()):
        if name not in header["arrays"]:
            if name in REQUIRED:
                _fail(path, name, "required array missing")
            continue
        a[name] = _locate(path, name, dtype, header["arrays"][name], buf)
    nn, mm = f"n = {n}", f"m = {m}"
    _expect_shape(path, "A.indptr", a["A.indptr"], [n + 1], f"{nn}, n + 1 entries")
    nnz_a = a["A.indices"].size
    _expect_shape(path, "A.indices", a["A.indices"], [nnz_a], "one dimension")
    if nnz_a > _MAX_INT32:
        _fail(path, "A.indices", f"nnz {nnz_a} > 2147483647 (indices are 32-bit)")
    _expect_shape(path, "A.data", a["A.data"], [nnz_a], "the length of A.indices")
    _expect_shape(path, "b", a["b"], [n], nn)
    _expect_shape(path, "x0", a["x0"], [n], nn)
    _expect_shape(path, "J.indptr", a["J.indptr"], [m + 1], f"{mm}, m + 1 entries")
    nnz_j = a["J.indices"].size
    _expect_shape(path, "J.indices", a["J.indices"], [nnz_j], "one dimension")
    _expect_shape(path, "J.data", a["J.data"], [nnz_j], "the length of J.indices")
    _expect_shape(path, "c", a["c"], [m], mm)
    for name, shape, why in (("contact.kind", [m], mm), ("contact.depth", [m], mm),
                             ("contact.vertex", [m, 4], f"{mm}, 4 vertices per row"), ("x_ref", [n], nn),
                             ("lambda_ref", [m], mm)):
        if name in a:
            _expect_shape(path, name, a[name], shape, why)
    # Friction: mu and the three T arrays come together; cT needs T, v0 needs h.
    t_names = ("T.indptr", "T.indices", "T.data")
    has_t = any(t in a for t in t_names)
    if has_t:
        for t in t_names:
            if t not in a:
                _fail(path, t, "missing (T is given as T.indptr, T.indices, T.data)")
    if "mu" in a and not has_t:
        _fail(path, "T", "missing: mu needs the two tangent rows per contact (T, 2m x n)")
    if has_t and "mu" not in a:
        _fail(path, "mu", "missing: T is given without friction coefficients")
    if "cT" in a and not has_t:
        _fail(path, "cT", "given without the tangent rows T")
    if "v0" in a and "h" not in header:
        _fail(path, "h", "missing: v0 is given without the step h")
    if "mu" in a:
        _expect_shape(path, "mu", a["mu"], [m], f"{mm}, one per contact row")
    if has_t:
        _expect_shape(path, "T.indptr", a["T.indptr"], [2 * m + 1], f"{mm}, two tangent rows per contact, 2m + 1 entries")
        nnz_t = a["T.indices"].size
        _expect_shape(path, "T.indices", a["T.indices"], [nnz_t], "one dimension")
        if nnz_t > _MAX_INT32:
            _fail(path, "T.indices", f"nnz {nnz_t} > 2147483647 (indices are 32-bit)")
        _expect_shape(path, "T.data", a["T.data"], [nnz_t], "the length of T.indices")
    if "cT" in a:
        _expect_shape(path, "cT", a["cT"], [2 * m], f"{mm}, two per contact")
    if "v0" in a:
        _expect_shape(path, "v0", a["v0"], [n], nn)
    rows_a = _check_csr(path, "A", a["A.indptr"], a["A.indices"], n, n)
    _check_csr(path, "J", a["J.indptr"], a["J.indices"], m, n)
    if has_t:
        _check_csr(path, "T", a["T.indptr"], a["T.indices"], 2 * m, n)
    for name in ("A.data", "b", "x0", "J.data", "c", "contact.depth", "x_ref", "lambda_ref", "mu", "T.data", "cT", "v0"):
        if name in a:
            bad = np.flatnonzero(~np.isfinite(a[name].ravel()))
            if bad.size:
                i = int(bad[0])
                _fail(path, name, f"non-finite value {_g17(a[name].ravel()[i])} at index {i}")
    if "mu" in a:
        bad = np.flatnonzero(a["mu"] < 0)
        if bad.size:
            r = int(bad[0])
            _fail(path, "mu", f"negative friction coefficient {_g17(a['mu'][r])} at contact {r}")
    if "contact.kind" in a:
        bad = np.flatnonzero((a["contact.kind"] < 0) | (a["contact.kind"] > 4))
        if bad.size:
            r = int(bad[0])
            _fail(path, "contact.kind", f"value {a['contact.kind'][r]} at row {r} is not a contact kind (0..4)")
    if "contact.depth" in a:
        bad = np.flatnonzero(a["contact.depth"] < 0)
        if bad.size:
            r = int(bad[0])
            _fail(path, "contact.depth", f"negative depth {_g17(a['contact.depth'][r])} at row {r}")
    if "contact.vertex" in a:
        bad = np.flatnonzero(a["contact.vertex"].ravel() < -1)
        if bad.size:
            e = int(bad[0])
            _fail(path, "contact.vertex", f"value {a['contact.vertex'].ravel()[e]} at row {e // 4} is not a vertex id or -1")
    a["A.indptr"], a["A.indices"], a["A.data"] = _symmetrise(path, n, a["A.indptr"], a["A.indices"], a["A.data"], rows_a)
    _check_diagonal(path, n, a["A.indptr"], a["A.indices"], a["A.data"])
    return {"path": path, "n": n, "m": m, "meta": header.get("meta", {}), "header": header, "arrays": a}


def _symmetrise(path, n, indptr, indices, data, rows):
    """Checks |A - A'| <= 1e-12 max|A_ij| (else names the worst pair) and returns (A + A') / 2."""
    max_abs = float(np.abs(data).max()) if data.size else 0.0
    tol = 1e-12 * max_abs
    key = rows.astype(np.int64) * n + indices
    tkey = indices.astype(np.int64) * n + rows
    order = np.argsort(tkey, kind="stable")   # the transpose, sorted in CSR order
    same_pattern = np.array_equal(tkey[order], key)
    if same_pattern:
        mirror = data[order]
        diff = np.abs(data - mirror)
        pairs_upper = indices > rows
        if diff.size and diff.max() > tol:
            # The worst pair, reported from its upper entry (i < j) as the C++ reader does.
            masked = np.where(pairs_upper, diff, -1.0)
            e = int(np.argmax(masked))
            i, j = int(rows[e]), int(indices[e])
            _fail(path, "A", f"not symmetric: A({i}, {j}) = {_g17(data[e])} but A({j}, {i}) = {_g17(mirror[e])} "
                             f"(difference {_g17(diff[e])} > 1e-12 * max|A_ij| = {_g17(tol)})")
        sym = np.where(data == mirror, data, 0.5 * data + 0.5 * mirror)
        return indptr, indices, sym
    # One-sided entries: union pattern through a dense-free merge of (key, value) lists.
    all_keys = np.concatenate([key, tkey])
    all_vals = np.concatenate([0.5 * data, 0.5 * data])
    uniq, inv = np.unique(all_keys, return_inverse=True)
    sym = np.zeros(uniq.size)
    np.add.at(sym, inv, all_vals)
    # Asymmetry per stored entry: A(i,j) - A(j,i), with 0 for a missing mirror.
    pos = np.searchsorted(key, tkey)
    pos_ok = (pos < key.size) & (key[np.minimum(pos, key.size - 1)] == tkey)
    mirror = np.where(pos_ok, data[np.minimum(pos, key.size - 1)], 0.0)
    diff = np.abs(data - mirror)
    if diff.size and diff.max() > tol:
        e = int(np.argmax(diff))
        i, j = int(rows[e]), int(indices[e])
        _fail(path, "A", f"not symmetric: A({i}, {j}) = {_g17(data[e])} but A({j}, {i}) = {_g17(mirror[e])} "
                         f"(difference {_g17(diff[e])} > 1e-12 * max|A_ij| = {_g17(tol)})")
    new_rows, new_cols = uniq // n, uniq % n
    new_indptr = np.zeros(n + 1, dtype=np.int64)
    np.add.at(new_indptr, new_rows + 1, 1)
    return np.cumsum(new_indptr), new_cols.astype(np.int64), sym


def _g17(v):
    """%.17g, as the C++ messages print numbers."""
    return "%.17g" % float(v)


def _check_diagonal(path, n, indptr, indices, data):
    rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    is_diag = rows == indices
    has = np.zeros(n, dtype=bool)
    has[rows[is_diag]] = True
    if not has.all():
        i = int(np.flatnonzero(~has)[0])
        _fail(path, "A", f"diagonal entry A({i}, {i}) is missing (A must be SPD)")
    diag = np.empty(n)
    diag[rows[is_diag]] = data[is_diag]
    bad = np.flatnonzero(~(diag > 0))
    if bad.size:
        i = int(bad[0])
        _fail(path, "A", f"diagonal entry A({i}, {i}) = {_g17(diag[i])} is not positive (A must be SPD)")


def matrices(snap):
    """(A, J) as scipy.sparse.csr_matrix (A symmetrised); needs scipy."""
    import scipy.sparse as sp
    a, n, m = snap["arrays"], snap["n"], snap["m"]
    A = sp.csr_matrix((a["A.data"], a["A.indices"], a["A.indptr"]), shape=(n, n))
    J = sp.csr_matrix((a["J.data"], a["J.indices"], a["J.indptr"]), shape=(m, n))
    return A, J


def tangents(snap):
    """T (2m x n, the two tangent rows of each contact) as scipy.sparse.csr_matrix, None when the
    snapshot has no friction; needs scipy."""
    import scipy.sparse as sp
    a, n, m = snap["arrays"], snap["n"], snap["m"]
    if "T.indptr" not in a:
        return None
    return sp.csr_matrix((a["T.data"], a["T.indices"], a["T.indptr"]), shape=(2 * m, n))


def content_hash(path):
    """Hex of the 64-bit FNV-1a of the file bytes (the C++ qpsnap_content_hash)."""
    h = 0xCBF29CE484222325
    with open(path, "rb") as f:
        data = f.read()
    for byte in data:
        h ^= byte
        h = (h * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return "%016x" % h


def _csr_arrays(path, name, M, rows, cols):
    """(indptr, indices, data) of M (scipy sparse or dense 2-D array) in CSR, duplicates summed, rows sorted."""
    try:
        import scipy.sparse as sp
        csr = sp.csr_matrix(M, dtype=np.float64)
        csr.sum_duplicates()
        csr.sort_indices()
        indptr, indices, data = csr.indptr, csr.indices, csr.data
        shape = csr.shape
    except ImportError:
        dense = np.asarray(M, dtype=np.float64)
        if dense.ndim != 2:
            _fail(path, name, f"expected a matrix, got an array of {dense.ndim} dimensions")
        shape = dense.shape
        r, c = np.nonzero(dense)
        indptr = np.zeros(shape[0] + 1, dtype=np.int64)
        np.add.at(indptr, r + 1, 1)
        indptr, indices, data = np.cumsum(indptr), c, dense[r, c]
    if tuple(shape) != (rows, cols):
        _fail(path, name, f"expected shape ({rows}, {cols}), got {tuple(shape)}")
    return (np.ascontiguousarray(indptr, dtype="<i8"), np.ascontiguousarray(indices, dtype="<i8"),
            np.ascontiguousarray(data, dtype="<f8"))


def _vector(path, name, v, size):
    arr = np.ascontiguousarray(np.asarray(v, dtype=np.float64).ravel(), dtype="<f8")
    if arr.size != size:
        _fail(path, name, f"expected {size} values, got {arr.size}")
    return arr


def write_qpsnap(path, A, b, J=None, c=None, x0=None, meta=None, x_ref=None, lambda_ref=None, mu=None, T=None,
                 cT=None, h=None, v0=None):
    """Writes min 1/2 x'Ax - b'x subject to Jx >= c as a .qpsnap (the C++ writer's layout).

    A (n x n) and J (m x n) are scipy sparse matrices or dense arrays; J None means no
    constraints; x0 defaults to zeros; meta is a JSON object. Friction (version 2): mu (m
    coefficients >= 0) with T (2m x n tangent rows), optional cT (2m), h (time step > 0) and v0
    (n, needs h); without any of them the file is version 1, as the C++ writer does. The file is written to a temporary
    name beside PATH and renamed, and read back with read_qpsnap before the rename, so a
    returned call means a snapshot the C++ reader takes (symmetric A, positive diagonal, finite
    values). Returns PATH.
    """
    import os
    import tempfile
    path = str(path)
    b = np.asarray(b, dtype=np.float64).ravel()
    n = b.size
    a_indptr, a_indices, a_data = _csr_arrays(path, "A", A, n, n)
    if J is None:
        j_indptr, j_indices, j_data = np.zeros(1, "<i8"), np.zeros(0, "<i8"), np.zeros(0, "<f8")
        m = 0
    else:
        m = np.shape(J)[0]
        j_indptr, j_indices, j_data = _csr_arrays(path, "J", J, m, n)
    arrays = [("A.indptr", "int64", a_indptr), ("A.indices", "int64", a_indices), ("A.data", "float64", a_data),
              ("b", "float64", _vector(path, "b", b, n)),
              ("x0", "float64", _vector(path, "x0", np.zeros(n) if x0 is None else x0, n)),
              ("J.indptr", "int64", j_indptr), ("J.indices", "int64", j_indices), ("J.data", "float64", j_data),
              ("c", "float64", _vector(path, "c", np.zeros(m) if c is None else c, m))]
    if x_ref is not None:
        arrays.append(("x_ref", "float64", _vector(path, "x_ref", x_ref, n)))
    if lambda_ref is not None:
        arrays.append(("lambda_ref", "float64", _vector(path, "lambda_ref", lambda_ref, m)))
    if mu is not None:
        arrays.append(("mu", "float64", _vector(path, "mu", mu, m)))
    if T is not None:
        t_indptr, t_indices, t_data = _csr_arrays(path, "T", T, 2 * m, n)
        arrays += [("T.indptr", "int64", t_indptr), ("T.indices", "int64", t_indices), ("T.data", "float64", t_data)]
    if cT is not None:
        arrays.append(("cT", "float64", _vector(path, "cT", cT, 2 * m)))
    if v0 is not None:
        arrays.append(("v0", "float64", _vector(path, "v0", v0, n)))
    version2 = any(v is not None for v in (mu, T, cT, h, v0))
    meta = {} if meta is None else meta
    if not isinstance(meta, dict):
        _fail(path, "meta", f"expected a JSON object (dict), got {type(meta).__name__}")
    entries, offset = {}, 0
    for name, dtype, arr in arrays:
        raw = arr.tobytes()
        entries[name] = {"dtype": dtype, "shape": [int(s) for s in arr.shape], "offset": offset,
                         "nbytes": len(raw), "crc32": zlib.crc32(raw) & 0xFFFFFFFF}
        offset += len(raw)
    header = {"format": "qpsnap", "version": 2 if version2 else 1, "n": int(n), "m": int(m), "arrays": entries,
              "meta": meta}
    if h is not None:
        header["h"] = float(h)
    text = json.dumps(header, separators=(",", ":"), allow_nan=False).encode("utf-8")
    text += b" " * ((8 - len(text) % 8) % 8)  # the data buffer starts 8-byte aligned
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=os.path.basename(path) + ".tmp.", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(len(text).to_bytes(8, "little"))
            f.write(text)
            for _, _, arr in arrays:
                f.write(arr.tobytes())
            f.flush()
            os.fsync(f.fileno())
        read_qpsnap(tmp)  # the reader's checks, before the name is taken
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path
