#!/usr/bin/env python3
"""Convert a local friction-contact problem from Siconos' text format (.dat) to FCLIB (HDF5).

Siconos keeps many of its test problems (numerics/src/FrictionContact/test/data/*.dat) in the text
format of `frictionContact_printInFile`: the dimension d, the number of contacts n_c, the matrix W
(a NumericsMatrix: dense or sparse-block), then q (m = d n_c values) and mu (n_c values). This
script reads that format and writes `/fclib_local/{W, vectors/q, vectors/mu, spacedim}` as
../shared/docs/fclib.md describes (W in compressed sparse column form, nz = -1), so that
`coulomb solve` / `coulomb bench` can run on these problems. Nothing is changed in the data: the
entries are written as read (no symmetrization, no zero dropped except the structural zeros of
a sparse-block matrix's missing blocks).

Supported storages of W: 0 (dense, column-major) and 1 (sparse block, blocks column-major).
Storage 2 (CSparse) is refused: Siconos prints it with six significant digits, too few to state a
problem whose error is measured at 1e-8.

Usage: siconos_dat_to_fclib.py IN.dat OUT.hdf5 [--title T]
Needs numpy and h5py (not dependencies of coulomb itself).
"""

import argparse
import os
import sys
import tempfile

import h5py
import numpy as np


class DatError(Exception):
    pass


class Tokens:
    """Whitespace-separated tokens of a text file, read in order."""

    def __init__(self, text, path):
        self.items = text.split()
        self.pos = 0
        self.path = path

    def next(self, what):
        if self.pos >= len(self.items):
            raise DatError(f"{self.path}: the file ends before {what}")
        tok = self.items[self.pos]
        self.pos += 1
        return tok

    def int(self, what):
        tok = self.next(what)
        try:
            return int(tok)
        except ValueError:
            raise DatError(f"{self.path}: expected an integer for {what}, found {tok!r}") from None

    def float(self, what):
        tok = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise DatError(f"{self.path}: expected a number for {what}, found {tok!r}") from None
        if not np.isfinite(value):
            raise DatError(f"{self.path}: {what} is not finite ({tok})")
        return value


def read_dense(tok, m):
    rows, cols = tok.int("the dense matrix's rows"), tok.int("the dense matrix's columns")
    if (rows, cols) != (m, m):
        raise DatError(f"{tok.path}: dense W is {rows}x{cols}, expected {m}x{m}")
    values = np.array([tok.float(f"W entry {k}") for k in range(m * m)])
    return values.reshape((m, m), order="F")


def read_sparse_block(tok, m):
    nbblocks = tok.int("the number of blocks")
    dense = np.zeros((m, m))
    if nbblocks == 0:
        return dense
    nrow, ncol = tok.int("the number of block rows"), tok.int("the number of block columns")
    row_ends = [tok.int(f"block row end {i}") for i in range(nrow)]
    col_ends = [tok.int(f"block column end {j}") for j in range(ncol)]
    increasing = lambda ends: all(a < b for a, b in zip([0] + ends, ends))
    if not row_ends or row_ends[-1] != m or not col_ends or col_ends[-1] != m:
        raise DatError(f"{tok.path}: block sizes do not add up to {m}")
    if not increasing(row_ends) or not increasing(col_ends):
        raise DatError(f"{tok.path}: block row or column ends are not increasing")
    filled1, filled2 = tok.int("filled1"), tok.int("filled2")
    if filled1 != nrow + 1 or filled2 != nbblocks:
        raise DatError(f"{tok.path}: filled1 = {filled1}, filled2 = {filled2} do not match "
                       f"{nrow} block rows and {nbblocks} blocks")
    index1 = [tok.int(f"index1 {k}") for k in range(filled1)]
    index2 = [tok.int(f"index2 {k}") for k in range(filled2)]
    if index1[0] != 0 or index1[-1] != nbblocks or any(a > b for a, b in zip(index1, index1[1:])):
        raise DatError(f"{tok.path}: the block row pointers are not increasing from 0 to {nbblocks}")
    for brow in range(nrow):
        r0 = row_ends[brow - 1] if brow else 0
        r1 = row_ends[brow]
        for blk in range(index1[brow], index1[brow + 1]):
            label = tok.int(f"the number of block {blk}")
            if label != blk:
                raise DatError(f"{tok.path}: block {blk} is labelled {label}")
            bcol = index2[blk]
            if not 0 <= bcol < ncol:
                raise DatError(f"{tok.path}: block {blk} has column {bcol} out of 0..{ncol}")
            c0 = col_ends[bcol - 1] if bcol else 0
            c1 = col_ends[bcol]
            values = [tok.float(f"entry of block {blk}") for _ in range((r1 - r0) * (c1 - c0))]
            dense[r0:r1, c0:c1] += np.array(values).reshape((r1 - r0, c1 - c0), order="F")
    return dense


def read_dat(path):
    with open(path) as fh:
        tok = Tokens(fh.read(), path)
    d = tok.int("the dimension")
    if d not in (2, 3):
        raise DatError(f"{path}: dimension {d}, expected 2 or 3")
    nc = tok.int("the number of contacts")
    if nc <= 0:
        raise DatError(f"{path}: {nc} contacts")
    m = d * nc
    storage = tok.int("the storage type of W")
    size0, size1 = tok.int("W's rows"), tok.int("W's columns")
    if (size0, size1) != (m, m):
        raise DatError(f"{path}: W is {size0}x{size1}, expected {m}x{m}")
    if storage == 0:
        w = read_dense(tok, m)
    elif storage == 1:
        w = read_sparse_block(tok, m)
    else:
        raise DatError(f"{path}: storage type {storage} of W is not supported (0 dense, 1 sparse block)")
    q = np.array([tok.float(f"q[{i}]") for i in range(m)])
    mu = np.array([tok.float(f"mu[{i}]") for i in range(nc)])
    return d, w, q, mu


def write_fclib(path, d, w, q, mu, title):
    m = w.shape[0]
    cols = [np.nonzero(w[:, j])[0] for j in range(m)]
    p = np.zeros(m + 1, dtype=np.int32)
    p[1:] = np.cumsum([len(c) for c in cols])
    i = np.concatenate(cols).astype(np.int32) if m else np.zeros(0, np.int32)
    x = np.concatenate([w[c, j] for j, c in enumerate(cols)])
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(suffix=".hdf5", dir=directory)
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            g = f.create_group("fclib_local")
            g["spacedim"] = np.array([d], dtype=np.int32)
            wg = g.create_group("W")
            wg["m"] = np.array([m], dtype=np.int32)
            wg["n"] = np.array([m], dtype=np.int32)
            wg["nz"] = np.array([-1], dtype=np.int32)
            wg["nzmax"] = np.array([len(x)], dtype=np.int32)
            wg["p"], wg["i"], wg["x"] = p, i, x
            v = g.create_group("vectors")
            v["q"], v["mu"] = q, mu
            info = g.create_group("info")
            info["title"] = title
            info["description"] = "converted from Siconos' text format by scripts/siconos_dat_to_fclib.py"
            info["math_info"] = ""
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--title", default=None)
    args = ap.parse_args()
    try:
        d, w, q, mu = read_dat(args.input)
    except (DatError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    title = args.title or os.path.basename(args.input)
    if os.path.abspath(args.output) == os.path.abspath(args.input):
        print("error: the output would replace the input", file=sys.stderr)
        return 2
    try:
        write_fclib(args.output, d, w, q, mu, title)
    except OSError as e:
        print(f"error: cannot write {args.output}: {e}", file=sys.stderr)
        return 2
    asym = np.abs(w - w.T).max() / max(np.abs(w).max(), 1e-300)
    print(f"{args.output}: d = {d}, {len(mu)} contacts, nnz(W) = {np.count_nonzero(w)}, "
          f"max|W - W^T| / max|W| = {asym:.2e}, mu in [{mu.min():g}, {mu.max():g}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
