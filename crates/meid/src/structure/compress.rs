//! Triplets to a compressed-column matrix, duplicates summed: the same matrix, bit for bit, as
//! faer's `SparseColMat::try_new_from_triplets`, with the sort kept in cache.
//!
//! # Why hand-written
//! faer 0.24 buckets the triplet indices by column, sorts each column's indices with a key that
//! reads the row back from the triplet array, and gathers the values from it again: at 10⁶ DOF
//! the stiffness has ~6 × 10⁷ triplets (1.4 GB, estimated), every key and every value is a
//! cache miss, and the conversion was 6 % of a `meid modes` run (docs/performance.md). Here
//! each column's entries are first copied next to each other as `(row << 32 | position in the
//! column)` keys with their values, and each column is sorted in place.
//!
//! # Same bits as faer
//! Within a column the entries stand in triplet order in both (a stable bucket pass), and both
//! sort them with `slice::sort_unstable_by_key` by row over 8-byte `Copy` elements (faer's
//! `usize` indices, our `u64` keys): the sort compares only rows, so it makes the same
//! comparisons and the same moves, and the entries of one row meet in the same order. Duplicates
//! are then summed left to right, `a + b`, as faer sums them. Test
//! `compressed_columns_equal_fairs_bit_for_bit` checks it on columns long enough for the
//! quicksort path, with many duplicates.

use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet};

use crate::{Error, Result};

/// Rows and per-column positions are packed into one `u64` key: both must fit in 32 bits.
const HALF: u32 = 32;
const LOW: u64 = (1 << HALF) - 1;

/// The `n × n` compressed-column matrix of the triplets `t`, duplicates summed (module docs).
/// `what` names the matrix in errors. Falls back to faer's builder when an index or a column's
/// length does not fit the 32-bit halves of the sort key.
pub fn compress(
    n: usize,
    t: &[Triplet<usize, usize, f64>],
    what: &str,
) -> Result<SparseColMat<usize, f64>> {
    let faer_route = || {
        SparseColMat::try_new_from_triplets(n, n, t)
            .map_err(|e| Error::numerical("assembly", format!("building sparse {what}: {e:?}")))
    };
    if let Some(e) = t.iter().find(|e| e.row >= n || e.col >= n) {
        return Err(Error::numerical(
            "assembly",
            format!(
                "building sparse {what}: entry ({}, {}) outside the {n} × {n} matrix",
                e.row, e.col
            ),
        ));
    }
    if n as u64 > LOW {
        return faer_route();
    }
    // Column starts (a counting pass), then each entry copied into its column in triplet order.
    let mut start = vec![0usize; n + 1];
    for e in t {
        start[e.col + 1] += 1;
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    if (0..n).any(|j| (start[j + 1] - start[j]) as u64 > LOW) {
        return faer_route();
    }
    let mut keys = vec![0u64; t.len()];
    let mut vals = vec![0.0f64; t.len()];
    let mut fill = start[..n].to_vec();
    for e in t {
        let s = fill[e.col];
        keys[s] = ((e.row as u64) << HALF) | (s - start[e.col]) as u64;
        vals[s] = e.val;
        fill[e.col] += 1;
    }

    // Each column sorted by row (module docs: the same comparisons as faer's), duplicates summed
    // left to right into the compressed rows and values.
    let mut col_ptr = vec![0usize; n + 1];
    let mut row_idx = Vec::with_capacity(t.len());
    let mut values = Vec::with_capacity(t.len());
    for j in 0..n {
        let (a, b) = (start[j], start[j + 1]);
        let column = &mut keys[a..b];
        column.sort_unstable_by_key(|&k| k >> HALF);
        let mut prev = u64::MAX;
        for &k in column.iter() {
            let row = k >> HALF;
            let v = vals[a + (k & LOW) as usize];
            if row == prev {
                if let Some(last) = values.last_mut() {
                    *last += v;
                }
            } else {
                row_idx.push(row as usize);
                values.push(v);
                prev = row;
            }
        }
        col_ptr[j + 1] = row_idx.len();
    }
    drop(keys);
    drop(vals);
    row_idx.shrink_to_fit();
    values.shrink_to_fit();
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    Ok(SparseColMat::new(symbolic, values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn compressed_columns_equal_fairs_bit_for_bit() {
        let mut rng = SplitMix64::new(7);
        for (n, len) in [(1, 5), (7, 400), (40, 6000), (300, 20000)] {
            // Few rows per column and many entries: long columns (the quicksort path, beyond
            // the small-sort threshold) with many duplicates of each row.
            let t: Vec<Triplet<usize, usize, f64>> = (0..len)
                .map(|_| {
                    let r = (rng.next_f64() * n as f64) as usize % n;
                    let c = (rng.next_f64() * n as f64) as usize % n;
                    let v = (rng.next_f64() - 0.5) * 10f64.powi((rng.next_f64() * 12.0) as i32 - 6);
                    Triplet::new(r, c, v)
                })
                .collect();
            let ours = compress(n, &t, "test").expect("compress");
            let faers = SparseColMat::try_new_from_triplets(n, n, &t).expect("faer");
            assert_eq!(ours.col_ptr(), faers.col_ptr(), "n = {n}");
            assert_eq!(ours.row_idx(), faers.row_idx(), "n = {n}");
            let bits = |a: &SparseColMat<usize, f64>| -> Vec<u64> {
                a.val().iter().map(|v| v.to_bits()).collect()
            };
            assert_eq!(bits(&ours), bits(&faers), "n = {n}");
        }
    }

    #[test]
    fn an_entry_outside_the_matrix_is_an_error_and_no_entries_an_empty_matrix() {
        let t = [Triplet::new(0, 3, 1.0)];
        let e = compress(3, &t, "stiffness").expect_err("outside");
        assert!(e.to_string().contains("outside the 3 × 3 matrix"), "{e}");
        let empty = compress(4, &[], "mass").expect("empty");
        assert_eq!(empty.col_ptr(), &[0, 0, 0, 0, 0]);
        assert!(empty.row_idx().is_empty());
    }
}
