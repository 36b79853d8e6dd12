# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
# distutils: language = c++
"""The Python layer's learning kernels: the Gaussian update and the greedy feature
selections (WMIL, MILBoost), called once per frame by ``wmiltrack.engine``.

Thin Cython bindings of the C++ core's ``wmiltrack/learning.hpp`` (where the C++ benchmarks
time them as part of a whole frame step): arguments are checked here, the GIL is released
for the work. The numbers are those of the numpy/Cython code they replaced, bit for bit
(numpy's pairwise sums and two-pass spread are reproduced), so that no tracker's boxes
moved. See ``wmiltrack.engine.classifier`` and ``wmiltrack.engine.selection`` for the
documented entry points and the numpy references they are tested against.
"""

import numpy as np

from libc.stdint cimport int32_t
from libcpp cimport bool as cbool


cdef extern from "wmiltrack/learning.hpp" namespace "wmiltrack" nogil:
    cdef cppclass MatrixView:
        const double* data
        int rows
        int cols
        Py_ssize_t row_stride
        Py_ssize_t col_stride

    cdef cppclass GaussianRule:
        double lam
        cbool first
        cbool direct_first
        cbool mil
        double sigma_floor

    void c_gaussian_update "wmiltrack::gaussian_update"(
        const MatrixView& values, const double* mu, const double* sigma,
        const GaussianRule& rule, double* new_mu, double* new_sigma,
        double* scratch) except +
    void c_wmil_select "wmiltrack::wmil_select"(
        const MatrixView& h_pos, const MatrixView& h_neg, const double* w_pos, int k,
        cbool code_gradient, int32_t* selected) except +
    void c_milboost_select "wmiltrack::milboost_select"(
        const MatrixView& h_pos, const MatrixView& h_neg, const MatrixView& exp_pos,
        const MatrixView& exp_neg, int k, double guard, int32_t* selected) except +


cdef MatrixView _view(const double[:, :] a):
    """A 2-D float64 memoryview as the core's strided matrix (strides in elements)."""
    cdef MatrixView v
    v.rows = <int>a.shape[0]
    v.cols = <int>a.shape[1]
    v.row_stride = a.strides[0] // sizeof(double)
    v.col_stride = a.strides[1] // sizeof(double)
    v.data = &a[0, 0] if a.shape[0] > 0 and a.shape[1] > 0 else NULL
    return v


cdef void _check_strides(const double[:, :] a, str name) except *:
    if a.strides[0] % sizeof(double) or a.strides[1] % sizeof(double):
        raise ValueError(f"{name}: strides must be whole float64 elements")


def wmil_select(const double[:, :] h_pos, const double[:, :] h_neg,
                const double[::1] w_pos, int k, bint code_gradient=False):
    """Greedy WMIL selection by the functional-gradient inner product (see selection.py)."""
    cdef Py_ssize_t M = h_pos.shape[0], P = h_pos.shape[1]
    if h_neg.shape[0] != M or w_pos.shape[0] != P:
        raise ValueError("h_pos, h_neg and w_pos disagree in shape")
    if k < 1 or k > M:
        raise ValueError(f"k must be in 1..{M}, got {k}")
    _check_strides(h_pos, "h_pos")
    _check_strides(h_neg, "h_neg")
    selected = np.empty(k, dtype=np.int32)
    cdef int[::1] sel = selected
    cdef MatrixView vp = _view(h_pos), vn = _view(h_neg)
    cdef const double* w = &w_pos[0] if P > 0 else NULL
    with nogil:
        c_wmil_select(vp, vn, w, k, code_gradient, <int32_t*>&sel[0])
    return selected


def milboost_select(const double[:, :] h_pos, const double[:, :] h_neg, int k,
                    double guard=1e-5):
    """Greedy MILBoost selection: Noisy-OR positive bag, each negative its own bag."""
    cdef Py_ssize_t M = h_pos.shape[0]
    if h_neg.shape[0] != M:
        raise ValueError("h_pos and h_neg disagree in shape")
    if k < 1 or k > M:
        raise ValueError(f"k must be in 1..{M}, got {k}")
    _check_strides(h_pos, "h_pos")
    _check_strides(h_neg, "h_neg")
    # exp(h) once per frame (numpy's exp), sample-major so the core's loops run over features:
    # clipped straight into the sample-major buffer, then exp in place (two passes, not four).
    Ep_a = np.empty((h_pos.shape[1], M))
    En_a = np.empty((h_neg.shape[1], M))
    np.exp(np.clip(np.asarray(h_pos).T, -300.0, 300.0, out=Ep_a), out=Ep_a)
    np.exp(np.clip(np.asarray(h_neg).T, -300.0, 300.0, out=En_a), out=En_a)
    selected = np.empty(k, dtype=np.int32)
    cdef int[::1] sel = selected
    cdef MatrixView vp = _view(h_pos), vn = _view(h_neg), ep = _view(Ep_a), en = _view(En_a)
    with nogil:
        c_milboost_select(vp, vn, ep, en, k, guard, <int32_t*>&sel[0])
    return selected


def gaussian_update(const double[:, :] values, const double[::1] mu, const double[::1] sigma,
                    double lam, bint first, bint direct_first, bint mil, double sigma_floor):
    """One class's Gaussians after a frame's samples ``values`` (M x n, n >= 1): (mu, sigma).

    ``mil=False`` (CT, FCT, WMIL, rcwmil, spec 1.1): the first update is direct when
    ``first and direct_first``; otherwise the moments are blended with weight ``lam`` on
    the old model. ``mil=True`` (MILTrack, spec 1.2): the variance is blended around the
    updated mean. The same bits as ``classifier.reference_update`` (numpy).
    """
    cdef Py_ssize_t M = values.shape[0], n = values.shape[1]
    if mu.shape[0] != M or sigma.shape[0] != M:
        raise ValueError("values, mu and sigma disagree in the number of features")
    if n < 1:
        raise ValueError("gaussian_update needs at least one sample")
    _check_strides(values, "values")
    new_mu_a = np.empty(M)
    new_sigma_a = np.empty(M)
    scratch_a = np.empty(n)
    cdef double[::1] new_mu = new_mu_a, new_sigma = new_sigma_a, scratch = scratch_a
    cdef GaussianRule rule
    rule.lam = lam
    rule.first = first
    rule.direct_first = direct_first
    rule.mil = mil
    rule.sigma_floor = sigma_floor
    cdef MatrixView v = _view(values)
    if M == 0:
        return new_mu_a, new_sigma_a
    with nogil:
        c_gaussian_update(v, &mu[0], &sigma[0], rule, &new_mu[0], &new_sigma[0], &scratch[0])
    return new_mu_a, new_sigma_a
