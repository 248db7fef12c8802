import os

import coulomb

f = coulomb.fclib.read("data/box-local.hdf5")      # .problem .solution .info
p = f.problem                                      # a LocalProblem: u = W r + q
W, q, mu = p.W, p.q, p.mu                          # scipy.sparse csc_array, numpy arrays
p2 = coulomb.LocalProblem(W, q, mu, dim=3)         # any numpy / scipy.sparse input
sol = coulomb.solve(p2, tol=1e-8, time_limit=10.0) # Settings fields as keywords
print(sol.status, sol.err, sol.outer_iterations)   # err of docs/error.md, from sol.r
print(coulomb.error(p2, sol.r))                    # the same measure for any candidate r
print(coulomb.check(p2).conclusion)                # 'exists', 'none' or 'unknown'
os.makedirs("out", exist_ok=True)
coulomb.fclib.write("out/box-solved-py.hdf5", p2, sol)  # atomic; h5py and Siconos read it
run = coulomb.granular.simulate("box", beads=200, steps=20)
print(len(run.steps), run.positions.shape)         # per-step statistics, final centres
