# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The Python layer's learning kernels, compiled with Cython: the Gaussian update and the
greedy feature selections.

They are the hottest part of the Python layer (per frame, 20 x 100 x 95 multiply-adds for
WMIL, 50 x 250 x ~93 Noisy-OR terms for MILBoost, and the mean and spread of 100-250 features
over each bag). The Gaussian update reproduces numpy's float64 ``mean``/``std`` bit for bit
(numpy's pairwise summation, two passes), so that moving it here changed no tracker's boxes.
See ``wmiltrack.engine.classifier`` and ``wmiltrack.engine.selection`` for the documented
entry points and the numpy references they are tested against.
"""

import numpy as np

from libc.math cimport exp, log, log1p, sqrt, INFINITY, isnan


cdef inline double _log_sigmoid_and_rest(double z, double* rest) noexcept nogil:
    """ln sigma(z), and 1 - sigma(z) into ``rest``, both without overflow and from one
    exp(-|z|) (1 - sigma(z) is exact for large z, where 1 - sigma would round to 0)."""
    cdef double e
    if z >= 0:
        e = exp(-z)
        rest[0] = e / (1.0 + e)
        return -log1p(e)
    e = exp(z)
    rest[0] = 1.0 / (1.0 + e)
    return z - log1p(e)


cdef void _normalised(const double* logv, const double* w, double* out, Py_ssize_t n) noexcept nogil:
    """out[j] = w[j] exp(logv[j]) / sum_m w[m] exp(logv[m]), computed without underflow."""
    cdef Py_ssize_t j
    cdef double top = -INFINITY
    cdef double total = 0.0
    for j in range(n):
        if w[j] > 0 and logv[j] > top:
            top = logv[j]
    if top == -INFINITY:
        for j in range(n):
            out[j] = 0.0
        return
    for j in range(n):
        out[j] = w[j] * exp(logv[j] - top)
        total += out[j]
    for j in range(n):
        out[j] /= total


cdef void _take(Py_ssize_t best, Py_ssize_t step, const double[:, :] h_pos,
                const double[:, :] h_neg, double[::1] H_pos, double[::1] H_neg,
                unsigned char[::1] used, int[::1] sel) noexcept nogil:
    """Add feature ``best`` to the strong classifier (the first unused one if ``best < 0``,
    i.e. when every candidate scored NaN)."""
    cdef Py_ssize_t m, j
    if best < 0:
        for m in range(used.shape[0]):
            if not used[m]:
                best = m
                break
    used[best] = 1
    sel[step] = <int>best
    for j in range(H_pos.shape[0]):
        H_pos[j] += h_pos[best, j]
    for j in range(H_neg.shape[0]):
        H_neg[j] += h_neg[best, j]


def wmil_select(const double[:, :] h_pos, const double[:, :] h_neg,
                const double[::1] w_pos, int k, bint code_gradient=False):
    """Greedy WMIL selection by the functional-gradient inner product (see selection.py)."""
    cdef Py_ssize_t M = h_pos.shape[0], P = h_pos.shape[1], N = h_neg.shape[1]
    if h_neg.shape[0] != M or w_pos.shape[0] != P:
        raise ValueError("h_pos, h_neg and w_pos disagree in shape")
    if k < 1 or k > M:
        raise ValueError(f"k must be in 1..{M}, got {k}")
    H_pos_a = np.zeros(P); H_neg_a = np.zeros(N)
    g_a = np.zeros(P + N)
    tmp_a = np.zeros(max(P, N)); ones_a = np.ones(max(N, 1))
    used_a = np.zeros(M, dtype=np.uint8)
    selected = np.empty(k, dtype=np.int32)
    # Instance-major copy of the log ratios (row j: every feature's h on instance j, the
    # positives then the negatives), so that the inner loop below runs over features: M
    # independent sums that the compiler vectorises, each still adding its terms in the
    # order j = 0, 1, ... (the same bits as a feature-by-feature loop).
    hT_a = np.empty((P + N, M))
    score_a = np.empty(M)
    rest_a = np.empty(max(P, N))
    cdef double[:, ::1] hT = hT_a
    cdef double[::1] H_pos = H_pos_a, H_neg = H_neg_a, g = g_a
    cdef double[::1] tmp = tmp_a, ones = ones_a, score_v = score_a, rest = rest_a
    cdef unsigned char[::1] used = used_a
    cdef int[::1] sel = selected
    cdef Py_ssize_t step, j, m, best
    cdef double best_score, gj, a0, a1, a2, a3, a4, a5, a6, a7
    cdef Py_ssize_t m0
    cdef double* g_pos
    cdef double* g_neg
    cdef double* sc
    cdef const double* row
    with nogil:
        for j in range(P):
            for m in range(M):
                hT[j, m] = h_pos[m, j]
        for j in range(N):
            for m in range(M):
                hT[P + j, m] = h_neg[m, j]
        g_pos = &g[0] if P + N > 0 else NULL
        g_neg = g_pos + P if P + N > 0 else NULL
        sc = &score_v[0]
        for step in range(k):
            # Positive bag: d ln(sum_j w_j sigma_j) / dH_j = w_j sigma_j (1 - sigma_j) / sum w sigma.
            if P > 0:
                for j in range(P):
                    tmp[j] = _log_sigmoid_and_rest(H_pos[j], &rest[j])
                _normalised(&tmp[0], &w_pos[0], g_pos, P)
                if code_gradient:
                    # The reference code's w sigma (1 - w sigma) / sum(w sigma) (spec 5, compat).
                    for j in range(P):
                        g_pos[j] = g_pos[j] * (1.0 - w_pos[j] * exp(tmp[j]))
                else:
                    for j in range(P):
                        g_pos[j] = g_pos[j] * rest[j]  # 1 - sigma(H), exact for large H
            # Negative bag: d ln(sum_j (1 - sigma_j)) / dH_j = -sigma_j (1 - sigma_j) / sum(1 - sigma).
            if N > 0:
                for j in range(N):
                    tmp[j] = _log_sigmoid_and_rest(-H_neg[j], &rest[j])
                _normalised(&tmp[0], &ones[0], g_neg, N)
                for j in range(N):
                    g_neg[j] = -g_neg[j] * rest[j]
            # score_m = sum_j h_mj g_j over the positives then the negatives, eight features at
            # a time in registers (each sum still adds its terms in the order j = 0, 1, ...).
            m0 = 0
            while m0 + 8 <= M:
                a0 = 0.0; a1 = 0.0; a2 = 0.0; a3 = 0.0; a4 = 0.0; a5 = 0.0; a6 = 0.0; a7 = 0.0
                for j in range(P + N):
                    row = &hT[j, m0]
                    gj = g[j]
                    a0 = a0 + row[0] * gj
                    a1 = a1 + row[1] * gj
                    a2 = a2 + row[2] * gj
                    a3 = a3 + row[3] * gj
                    a4 = a4 + row[4] * gj
                    a5 = a5 + row[5] * gj
                    a6 = a6 + row[6] * gj
                    a7 = a7 + row[7] * gj
                sc[m0] = a0; sc[m0 + 1] = a1; sc[m0 + 2] = a2; sc[m0 + 3] = a3
                sc[m0 + 4] = a4; sc[m0 + 5] = a5; sc[m0 + 6] = a6; sc[m0 + 7] = a7
                m0 += 8
            for m in range(m0, M):
                a0 = 0.0
                for j in range(P + N):
                    a0 = a0 + hT[j, m] * g[j]
                sc[m] = a0
            best = -1
            best_score = -INFINITY
            for m in range(M):
                if used[m] or isnan(sc[m]):
                    continue
                if best < 0 or sc[m] > best_score:
                    best = m
                    best_score = sc[m]
            _take(best, step, h_pos, h_neg, H_pos, H_neg, used, sel)
    return selected


def milboost_select(const double[:, :] h_pos, const double[:, :] h_neg, int k,
                    double guard=1e-5):
    """Greedy MILBoost selection: Noisy-OR positive bag, each negative its own bag."""
    cdef Py_ssize_t M = h_pos.shape[0], P = h_pos.shape[1], N = h_neg.shape[1]
    if h_neg.shape[0] != M:
        raise ValueError("h_pos and h_neg disagree in shape")
    if k < 1 or k > M:
        raise ValueError(f"k must be in 1..{M}, got {k}")
    # exp(h) once per frame, sample-major so the inner loops run over features.
    Ep_a = np.exp(np.clip(np.asarray(h_pos).T, -300.0, 300.0)).copy()
    En_a = np.exp(np.clip(np.asarray(h_neg).T, -300.0, 300.0)).copy()
    H_pos_a = np.zeros(P); H_neg_a = np.zeros(N)
    D_a = np.empty(M); prod_a = np.empty(M); L_a = np.empty(M)
    used_a = np.zeros(M, dtype=np.uint8)
    selected = np.empty(k, dtype=np.int32)
    cdef double[:, ::1] Ep = Ep_a, En = En_a
    cdef double[::1] H_pos = H_pos_a, H_neg = H_neg_a
    cdef double[::1] Dv = D_a, prodv = prod_a, Lv = L_a
    cdef unsigned char[::1] used = used_a
    cdef int[::1] sel = selected
    cdef double* Dp = &Dv[0]
    cdef double* pp = &prodv[0]
    cdef double* Lp = &Lv[0]
    cdef const double* e
    cdef Py_ssize_t step, j, m, best, chunk
    cdef double c, t, nll, best_nll, hz
    cdef double inv_p = 1.0 / P if P > 0 else 0.0
    cdef double inv_n = 1.0 / N if N > 0 else 0.0
    with nogil:
        for step in range(k):
            for m in range(M):
                Dp[m] = 1.0
                pp[m] = 1.0
                Lp[m] = 0.0
            # Positive bag: prod_j (1 - sigma(H_j + h_mj)) = 1 / prod_j (1 + e^H_j e^h_mj).
            # Capping the product at 1e30 changes 1 - 1/D by < 1e-30, far below the guard.
            for j in range(P):
                hz = H_pos[j]
                c = exp(60.0 if hz > 60.0 else (-60.0 if hz < -60.0 else hz))
                e = &Ep[j, 0]
                for m in range(M):
                    t = Dp[m] * (1.0 + c * e[m])
                    Dp[m] = t if t < 1e30 else 1e30
            # Negatives: sum_j ln(guard + 1 - sigma), as logs of products of <= 60 factors
            # (each factor >= guard = 1e-5, so a product stays above 1e-300).
            chunk = 0
            for j in range(N):
                hz = H_neg[j]
                c = exp(60.0 if hz > 60.0 else (-60.0 if hz < -60.0 else hz))
                e = &En[j, 0]
                for m in range(M):
                    pp[m] = pp[m] * (guard + 1.0 / (1.0 + c * e[m]))
                chunk += 1
                if chunk == 60 or j == N - 1:
                    for m in range(M):
                        Lp[m] += log(pp[m])
                        pp[m] = 1.0
                    chunk = 0
            best = -1
            best_nll = INFINITY
            for m in range(M):
                if used[m]:
                    continue
                nll = 0.0
                if P > 0:
                    nll = -log(1.0 - 1.0 / Dp[m] + guard) * inv_p
                nll = nll - Lp[m] * inv_n
                if isnan(nll):
                    continue
                if best < 0 or nll < best_nll:
                    best = m
                    best_nll = nll
            _take(best, step, h_pos, h_neg, H_pos, H_neg, used, sel)
    return selected


# -- Gaussian update ------------------------------------------------------------------------
cdef double _pairwise_sum(const double* a, Py_ssize_t n, Py_ssize_t stride) noexcept nogil:
    """numpy's float64 pairwise summation (blocks of <= 128 with 8 partial sums), exactly."""
    cdef double r0, r1, r2, r3, r4, r5, r6, r7, res
    cdef Py_ssize_t i, n2
    if n < 8:
        res = 0.0
        for i in range(n):
            res = res + a[i * stride]
        return res
    if n <= 128:
        r0 = a[0]; r1 = a[stride]; r2 = a[2 * stride]; r3 = a[3 * stride]
        r4 = a[4 * stride]; r5 = a[5 * stride]; r6 = a[6 * stride]; r7 = a[7 * stride]
        i = 8
        while i < n - (n % 8):
            r0 = r0 + a[i * stride]
            r1 = r1 + a[(i + 1) * stride]
            r2 = r2 + a[(i + 2) * stride]
            r3 = r3 + a[(i + 3) * stride]
            r4 = r4 + a[(i + 4) * stride]
            r5 = r5 + a[(i + 5) * stride]
            r6 = r6 + a[(i + 6) * stride]
            r7 = r7 + a[(i + 7) * stride]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res = res + a[i * stride]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise_sum(a, n2, stride) + _pairwise_sum(a + n2 * stride, n - n2, stride)


cdef inline double _row_sum(const double[:, :] values, Py_ssize_t m) noexcept nogil:
    """``numpy.add.reduce`` of row m: 0.0 plus the pairwise sum of its entries."""
    cdef Py_ssize_t n = values.shape[1]
    if n == 0:
        return 0.0
    return 0.0 + _pairwise_sum(&values[m, 0], n, values.strides[1] // sizeof(double))


cdef double _row_sq_dev_mean(const double[:, :] values, Py_ssize_t m, double centre,
                             double* scratch) noexcept nogil:
    """``((row - centre) ** 2).mean()`` as numpy computes it."""
    cdef Py_ssize_t j, n = values.shape[1]
    cdef double d
    for j in range(n):
        d = values[m, j] - centre
        scratch[j] = d * d
    return (0.0 + _pairwise_sum(scratch, n, 1)) / <double>n


cdef inline double _max_nan(double a, double b) noexcept nogil:
    """``numpy.maximum(a, b)`` (NaN propagates)."""
    if isnan(a) or a >= b:
        return a
    return b


def gaussian_update(const double[:, :] values, const double[::1] mu, const double[::1] sigma,
                    double lam, bint first, bint direct_first, bint mil, double sigma_floor):
    """One class's Gaussians after a frame's samples ``values`` (M x n, n >= 1): (mu, sigma).

    ``mil=False`` (CT, FCT, WMIL, rcwmil, spec 1.1): the first update is direct when
    ``first and direct_first``; otherwise the moments are blended with weight ``lam`` on
    the old model. ``mil=True`` (MILTrack, spec 1.2): the variance is blended around the
    updated mean. The same bits as ``classifier.reference_update`` (numpy).
    """
    cdef Py_ssize_t M = values.shape[0], n = values.shape[1], m
    if mu.shape[0] != M or sigma.shape[0] != M:
        raise ValueError("values, mu and sigma disagree in the number of features")
    if n < 1:
        raise ValueError("gaussian_update needs at least one sample")
    new_mu_a = np.empty(M)
    new_sigma_a = np.empty(M)
    scratch_a = np.empty(n)
    cdef double[::1] new_mu = new_mu_a, new_sigma = new_sigma_a, scratch = scratch_a
    cdef double mean, var, s, d, nd = <double>n
    cdef double keep = 1.0 - lam
    cdef double cross = lam * (1.0 - lam)
    with nogil:
        for m in range(M):
            mean = _row_sum(values, m) / nd
            if mil:
                if first:
                    var = _row_sq_dev_mean(values, m, mean, &scratch[0]) + 1e-9
                    new_mu[m] = mean
                else:
                    new_mu[m] = lam * mu[m] + keep * mean
                    var = lam * (sigma[m] * sigma[m]) + keep * _row_sq_dev_mean(values, m, new_mu[m], &scratch[0])
                new_sigma[m] = _max_nan(sqrt(var), sigma_floor)
                continue
            s = sqrt(_row_sq_dev_mean(values, m, mean, &scratch[0]))  # numpy's std
            if first and direct_first:
                new_mu[m] = mean
                new_sigma[m] = _max_nan(s, sigma_floor)
                continue
            d = mu[m] - mean
            var = (lam * (sigma[m] * sigma[m]) + keep * (s * s)) + cross * (d * d)
            new_sigma[m] = _max_nan(sqrt(var), sigma_floor)
            new_mu[m] = lam * mu[m] + keep * mean
    return new_mu_a, new_sigma_a
