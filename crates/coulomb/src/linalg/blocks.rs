//! Small d × d blocks (d = 2 or 3, one per contact), stored row-major one after the other:
//! block-diagonal products and the inverse of one block by cofactors.

/// out = blockdiag(blocks) x (row-major d × d blocks).
pub(crate) fn apply_blocks(d: usize, blocks: &[f64], x: &[f64], out: &mut [f64]) {
    for ((blk, xi), oi) in blocks.chunks(d * d).zip(x.chunks(d)).zip(out.chunks_mut(d)) {
        for a in 0..d {
            oi[a] = (0..d).map(|b| blk[a * d + b] * xi[b]).sum();
        }
    }
}

/// The inverse of a 2 × 2 or 3 × 3 row-major matrix by cofactors; None if its determinant
/// vanishes (or underflows) or is not finite.
pub(crate) fn invert_small(d: usize, a: &[f64], inv: &mut [f64]) -> Option<()> {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if d == 2 {
        let det = a[0] * a[3] - a[1] * a[2];
        if det.is_nan() || det.abs() <= f64::MIN_POSITIVE * scale * scale || !det.is_finite() {
            return None;
        }
        inv.copy_from_slice(&[a[3] / det, -a[1] / det, -a[2] / det, a[0] / det]);
        return Some(());
    }
    let c = |r: usize, k: usize| a[r * 3 + k];
    let cof = [
        c(1, 1) * c(2, 2) - c(1, 2) * c(2, 1),
        c(1, 2) * c(2, 0) - c(1, 0) * c(2, 2),
        c(1, 0) * c(2, 1) - c(1, 1) * c(2, 0),
    ];
    let det = c(0, 0) * cof[0] + c(0, 1) * cof[1] + c(0, 2) * cof[2];
    if det.is_nan() || det.abs() <= f64::MIN_POSITIVE * scale * scale * scale || !det.is_finite() {
        return None;
    }
    let adj = [
        cof[0],
        c(0, 2) * c(2, 1) - c(0, 1) * c(2, 2),
        c(0, 1) * c(1, 2) - c(0, 2) * c(1, 1),
        cof[1],
        c(0, 0) * c(2, 2) - c(0, 2) * c(2, 0),
        c(0, 2) * c(1, 0) - c(0, 0) * c(1, 2),
        cof[2],
        c(0, 1) * c(2, 0) - c(0, 0) * c(2, 1),
        c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0),
    ];
    for k in 0..9 {
        inv[k] = adj[k] / det;
    }
    Some(())
}
