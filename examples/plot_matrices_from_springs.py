"""
Building M, L and J from A_i and S_i
====================================

The paper writes the matrices with incidence vectors A_i ∈ Rⁿ (+1 at a_i, −1 at b_i) and
indicators S_i ∈ Rˢ::

    M = diag(m) ⊗ I3,   L = (Σ k_i A_i A_iᵀ) ⊗ I3,   J = (Σ k_i A_i S_iᵀ) ⊗ I3.

:mod:`clothsim.reference` builds them with exactly these loops (dense, slow, obviously
right); :mod:`clothsim.matrices` builds the same sparse matrices in one vectorized pass,
and the solvers use the n × n forms (``expand=False``) with three right-hand sides.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim import matrices, reference
from clothsim.gallery import grid_cloth

model = grid_cloth(4)                      # 16 vertices, 4 × 4 grid springs
n, s = model.vertex_count, model.spring_count
print(f"n = {n} vertices, s = {s} springs")

# %%
# Loop reference against the fast matrices: identical entries.
M_ref, L_ref, J_ref = (reference.mass_matrix(model), reference.stiffness_matrix(model),
                       reference.spring_matrix(model))
M, L, J = matrices.mass_matrix(model), matrices.stiffness_matrix(model), \
    matrices.spring_matrix(model)
for ref, fast in ((M_ref, M), (L_ref, L), (J_ref, J)):
    assert ref.shape == fast.shape
    assert np.allclose(ref, fast.toarray(), rtol=1e-14, atol=0)
assert L_ref.shape == (3 * n, 3 * n) and J_ref.shape == (3 * n, 3 * s)

# %%
# The 3n form is the n × n form ⊗ I3 (x stacked per vertex, x0 y0 z0 x1 …): the x, y and
# z columns never mix, so one n × n solve per column gives the same answer.
Ls = matrices.stiffness_matrix(model, expand=False).toarray()
assert np.allclose(np.kron(Ls, np.eye(3)), L_ref)
rng = np.random.default_rng(0)
x = rng.standard_normal((n, 3))
assert np.allclose((L_ref @ x.ravel()).reshape(n, 3), Ls @ x)

# %%
# L is a graph Laplacian (rows sum to zero: translations cost no spring energy) and
# L x = J p(x) with p_i = x_a − x_b.
assert np.allclose(L_ref.sum(axis=1), 0)
p = (x[model.springs.spring_vertices[:, 0]] - x[model.springs.spring_vertices[:, 1]])
assert np.allclose(L_ref @ x.ravel(), J_ref @ p.ravel())

fig, axes = plt.subplots(1, 2, figsize=(7, 3.4))
axes[0].spy(Ls, markersize=3)
axes[0].set_title("L_s (n × n)")
axes[1].spy(L_ref, markersize=1)
axes[1].set_title("L = L_s ⊗ I3 (3n × 3n)")
fig.tight_layout()
