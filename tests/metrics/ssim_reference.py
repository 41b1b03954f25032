#!/usr/bin/env python3
"""Reference values for tests/metrics/test_evaluation.cpp, from an implementation independent of
edgeplane: scipy's linear_sum_assignment for the D2MC matching and scikit-image's
structural_similarity for the SSIM (plus a plain re-reading of the SegComp and precision / recall
rules, as a cross-check of the region metrics).  The test itself does not need Python; re-run this script
(pip install numpy scipy scikit-image) when the test images or EVALUATION.md change, and paste the
printed values into the test.

The label images are built by integer formulas that test_evaluation.cpp repeats exactly
(make_reference_scene there).  Rendering and downsampling follow EVALUATION.md and Wang et al.'s
ssim.m:
  * render after the D2MC matching: label 0 -> 0, GT rank r (1-based, GT ids on scored pixels,
    ascending) -> 1 + (97 r mod 255), matched segment -> its GT's level, unmatched segments (ids on
    scored pixels) in ascending id order j = 1, 2, ... -> level of rank G + j; unscored -> 0;
  * F = max(1, round(min(rows, cols) / 256)) with MATLAB's round (halves away from zero);
  * imfilter(img, ones(F)/F^2, 'symmetric', 'same'): MATLAB anchors the F x F kernel at
    floor((F + 1) / 2), so output (y, x) averages rows y-(c-1) .. y+F-c (same for columns),
    c = floor((F + 1) / 2), mirrored past the border (numpy's 'symmetric' pad); then every F-th
    pixel from the first;
  * skimage.metrics.structural_similarity(gaussian_weights=True, sigma=1.5,
    use_sample_covariance=False, data_range=255, K1=0.01, K2=0.03): its window is 11x11
    (radius int(3.5 * 1.5 + 0.5) = 5) and it averages the map cropped by 5 pixels on every side,
    which is exactly 'valid' filtering.  The script checks that against a direct 'valid'
    implementation in numpy.
"""
import numpy as np
from scipy.optimize import linear_sum_assignment
from skimage.metrics import structural_similarity


def make_reference_scene(W, H):
    """pred, gt (uint16) and scored (bool) images of H rows and W columns."""
    y, x = np.mgrid[0:H, 0:W].astype(np.int64)

    def sx(v):
        return v * W // 300

    def sy(v):
        return v * H // 260

    def box(x0, x1, y0, y1):
        return (x >= sx(x0)) & (x < sx(x1)) & (y >= sy(y0)) & (y < sy(y1))

    diagonal = 5 * (x * H + y * W) < W * H
    hidden = box(200, 230, 130, 160)  # unscored block

    gt = np.full((H, W), 10, np.int64)           # wall
    gt[y >= sy(180)] = 50                        # floor
    gt[box(40, 140, 30, 120)] = 20
    gt[box(160, 280, 20, 100)] = 35
    gt[diagonal] = 60
    gt[box(100, 130, 140, 170)] = 0              # scored, but no plane
    gt[hidden] = 77                              # a GT plane with no scored pixel

    scored = ~(((x * 7 + y * 13) % 97 == 0) | hidden)

    pred = np.full((H, W), 1, np.int64)
    pred[y >= sy(183)] = 7
    pred[box(43, 143, 32, 122)] = 3
    split = box(158, 280, 22, 100)
    pred[split & (x < sx(225))] = 4
    pred[split & (x >= sx(225))] = 9
    pred[diagonal] = np.where((x + y) % 3 == 0, 0, 11)[diagonal]
    pred[box(10, 30, 140, 160)] = 12              # spurious segment
    pred[hidden] = 15                             # a segment on unscored pixels only
    pred[(x * x + 3 * y) % 53 == 0] = 0           # holes
    return pred.astype(np.uint16), gt.astype(np.uint16), scored


def grey(r):
    return 1 + (97 * r) % 255


def d2mc_and_render(pred, gt, scored):
    p, g = pred[scored], gt[scored]
    seg_ids = np.unique(p[p != 0])
    gt_ids = np.unique(g[g != 0])
    O = np.zeros((len(seg_ids), len(gt_ids)), np.int64)
    for a, m in enumerate(seg_ids):
        for b, n in enumerate(gt_ids):
            O[a, b] = np.count_nonzero((p == m) & (g == n))
    rows, cols = linear_sum_assignment(O, maximize=True)
    matches = [(int(seg_ids[a]), int(gt_ids[b]), int(O[a, b])) for a, b in zip(rows, cols) if O[a, b] > 0]
    covered = np.count_nonzero((p == 0) & (g == 0)) + sum(o for _, _, o in matches)
    d2mc = covered / p.size

    G = len(gt_ids)
    gt_level = {int(n): grey(r + 1) for r, n in enumerate(gt_ids)}
    matched = {m: gt_level[n] for m, n, _ in matches}
    pred_level, j = {}, 0
    for m in seg_ids:
        m = int(m)
        if m in matched:
            pred_level[m] = matched[m]
        else:
            j += 1
            pred_level[m] = grey(G + j)
    a = np.zeros(pred.shape, np.uint8)
    b = np.zeros(gt.shape, np.uint8)
    for m, v in pred_level.items():
        a[(pred == m) & scored] = v
    for n, v in gt_level.items():
        b[(gt == n) & scored] = v
    return d2mc, matches, a, b


def region_metrics(pred, gt, scored, T=0.8):
    """SegComp counts and plane precision / recall as EVALUATION.md reads, written plainly."""
    p, g = pred[scored], gt[scored]
    seg_ids = [int(m) for m in np.unique(p[p != 0])]
    gt_ids = [int(n) for n in np.unique(g[g != 0])]
    P_m = {m: np.count_nonzero(p == m) for m in seg_ids}
    P_n = {n: np.count_nonzero(g == n) for n in gt_ids}
    # Fragment rule: fewer scored pixels than pixels on unscored GT-0 pixels -> left out.
    dont_care = {m: np.count_nonzero((pred == m) & ~scored & (gt == 0)) for m in seg_ids}
    segs = [m for m in seg_ids if not P_m[m] < dont_care[m]]
    O = {(m, n): np.count_nonzero((p == m) & (g == n)) for m in segs for n in gt_ids}
    used_m, used_n = set(), set()
    correct = over = under = 0
    for m in segs:
        for n in gt_ids:
            if n not in used_n and m not in used_m and O[m, n] > 0 and O[m, n] >= T * P_m[m] and O[m, n] >= T * P_n[n]:
                used_m.add(m); used_n.add(n); correct += 1
    for n in gt_ids:
        if n in used_n:
            continue
        ms = [m for m in segs if m not in used_m and O[m, n] > 0 and O[m, n] >= T * P_m[m]]
        if len(ms) >= 2 and sum(O[m, n] for m in ms) >= T * P_n[n]:
            used_n.add(n); used_m.update(ms); over += 1
    for m in segs:
        if m in used_m:
            continue
        ns = [n for n in gt_ids if n not in used_n and O[m, n] > 0 and O[m, n] >= T * P_n[n]]
        if len(ns) >= 2 and sum(O[m, n] for n in ns) >= T * P_m[m]:
            used_m.add(m); used_n.update(ns); under += 1
    missed = len([n for n in gt_ids if n not in used_n])
    noise = len([m for m in segs if m not in used_m])
    pairs = sorted(((O[m, n] / (P_m[m] + P_n[n] - O[m, n]), m, n) for m in segs for n in gt_ids
                    if O[m, n] > 0 and 2 * O[m, n] >= P_m[m] + P_n[n] - O[m, n]), key=lambda t: (-t[0], t[1], t[2]))
    got_m, got_n, ious = set(), set(), []
    for iou, m, n in pairs:
        if m not in got_m and n not in got_n:
            got_m.add(m); got_n.add(n); ious.append(iou)
    return dict(correct=correct, over=over, under=under, missed=missed, noise=noise, segments=len(segs),
                matches=len(ious), mean_iou=float(np.mean(ious)) if ious else float('nan'))


def downsample(img):
    rows, cols = img.shape
    f = max(1, int(np.floor(min(rows, cols) / 256 + 0.5)))  # MATLAB round, not Python's
    if f == 1:
        return img.astype(np.float64), f
    c = (f + 1) // 2
    padded = np.pad(img.astype(np.float64), ((c - 1, f - c), (c - 1, f - c)), mode='symmetric')
    out = np.zeros(img.shape, np.float64)
    for dy in range(f):
        for dx in range(f):
            out += padded[dy:dy + rows, dx:dx + cols]
    out /= f * f
    return out[::f, ::f], f


def ssim_valid_numpy(a, b):
    """Direct 'valid' filtering with the 11x11 Gaussian, to check skimage's border handling."""
    k = np.exp(-((np.arange(11) - 5.0) ** 2) / (2 * 1.5 ** 2))
    w = np.outer(k, k)
    w /= w.sum()

    def filt(img):
        from numpy.lib.stride_tricks import sliding_window_view
        return np.einsum('ijkl,kl->ij', sliding_window_view(img, (11, 11)), w)

    c1, c2 = (0.01 * 255) ** 2, (0.03 * 255) ** 2
    mx, my = filt(a), filt(b)
    vx, vy, cxy = filt(a * a) - mx * mx, filt(b * b) - my * my, filt(a * b) - mx * my
    s = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
    return s.mean()


def main():
    for W, H in [(300, 260), (701, 541), (820, 700)]:
        pred, gt, scored = make_reference_scene(W, H)
        d2mc, matches, a, b = d2mc_and_render(pred, gt, scored)
        da, f = downsample(a)
        db, _ = downsample(b)
        s = structural_similarity(da, db, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                  data_range=255, K1=0.01, K2=0.03)
        s_valid = ssim_valid_numpy(da, db)
        assert abs(s - s_valid) < 1e-12, (s, s_valid)
        print(f'{W}x{H}: F={f} downsampled={da.shape[1]}x{da.shape[0]} scored={int(scored.sum())}')
        print(f'  matches (segment, gt, overlap) = {matches}')
        print(f'  D2MC = {d2mc:.17g}')
        print(f'  SSIM = {s:.17g}   (numpy valid: {s_valid:.17g})')
        print(f'  region metrics = {region_metrics(pred, gt, scored)}')


if __name__ == '__main__':
    main()
