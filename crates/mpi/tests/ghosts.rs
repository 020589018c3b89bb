//! Ghosted vectors and collectives against closed forms, at any number of ranks (run under
//! `mpirun -n N`; .ci/run-mpi-tests). Rank r owns 5 + r consecutive entries and ghosts the first
//! entry of every other rank and the last entry of the next rank, so an entry's number of
//! sharers is known in closed form.

mod common;

use common::distributed::{Case, ensure, run};
use saddle_mpi::{
    GhostVector, Index, Petsc, broadcast, broadcast_bytes, max, min, scatter_bytes, scatter_bytes_in_chunks, sum,
    sum_in_place,
};
use std::ops::Range;
use std::process::ExitCode;

/// The entries each rank owns: 5 + r for rank r, ranks in order.
fn ranges(size: usize) -> Vec<Range<usize>> {
    let mut start = 0;
    (0..size)
        .map(|r| {
            let range = start..start + 5 + r;
            start = range.end;
            range
        })
        .collect()
}

/// The ghosts of `rank`: the first entry of every other rank, then the last entry of the next.
fn ghosts(rank: usize, ranges: &[Range<usize>]) -> Vec<Index> {
    let size = ranges.len();
    let mut g: Vec<Index> = (0..size).filter(|&q| q != rank).map(|q| ranges[q].start as Index).collect();
    let next = (rank + 1) % size;
    if next != rank {
        g.push((ranges[next].end - 1) as Index);
    }
    g
}

/// How many ranks ghost the entry `i` owned by rank `q`: its first entry is ghosted by every
/// other rank, its last by the previous rank (when there is one other rank at least).
fn sharers(i: usize, q: usize, ranges: &[Range<usize>]) -> usize {
    let size = ranges.len();
    let first = if i == ranges[q].start { size - 1 } else { 0 };
    let last = if i == ranges[q].end - 1 && size > 1 { 1 } else { 0 };
    first + last
}

/// A vector of this layout, the owned ranges of all ranks and this rank's ghosts.
type Ghosted = (GhostVector, Vec<Range<usize>>, Vec<Index>);

fn vector(petsc: &Petsc) -> Result<Ghosted, String> {
    let ranges = ranges(petsc.size());
    let g = ghosts(petsc.rank(), &ranges);
    let v = GhostVector::new(petsc, ranges[petsc.rank()].len(), &g).map_err(|e| e.to_string())?;
    ensure(v.owned_range() == ranges[petsc.rank()], format!("owned range {:?}", v.owned_range()))?;
    ensure(v.ghost_len() == g.len(), format!("ghosts {}", v.ghost_len()))?;
    Ok((v, ranges, g))
}

/// Reverse update (ADD): each rank puts 1 in every ghost; each owner receives the number of
/// ranks sharing the entry.
fn reverse_add(petsc: &Petsc) -> Result<(), String> {
    let (mut v, ranges, g) = vector(petsc)?;
    let owned = v.owned_len();
    {
        let mut local = v.local_mut().map_err(|e| e.to_string())?;
        local.fill(0.0);
        local[owned..].fill(1.0);
    }
    v.accumulate_ghosts().map_err(|e| e.to_string())?;
    let local = v.local().map_err(|e| e.to_string())?;
    let rank = petsc.rank();
    for (k, i) in ranges[rank].clone().enumerate() {
        let expected = sharers(i, rank, &ranges) as f64;
        ensure(
            local[k] == expected,
            format!("rank {rank}: entry {i} = {} after reverse add, expected {expected}", local[k]),
        )?;
    }
    // conservation: what the owners received is what the ghosts sent
    let received: f64 = local[..owned].iter().sum();
    let sent = sum(petsc.world(), g.len());
    ensure(sum(petsc.world(), received) == sent as f64, format!("received {received} of {sent}"))
}

/// Forward update (INSERT): each ghost takes its owner's value 1.5·i.
fn forward_insert(petsc: &Petsc) -> Result<(), String> {
    let (mut v, ranges, g) = vector(petsc)?;
    let range = ranges[petsc.rank()].clone();
    {
        let mut local = v.local_mut().map_err(|e| e.to_string())?;
        for (k, i) in range.clone().enumerate() {
            local[k] = 1.5 * i as f64;
        }
        local[range.len()..].fill(-1.0);
    }
    v.update_ghosts().map_err(|e| e.to_string())?;
    let local = v.local().map_err(|e| e.to_string())?;
    for (k, &i) in g.iter().enumerate() {
        let got = local[range.len() + k];
        ensure(got == 1.5 * i as f64, format!("ghost of {i} = {got}, expected {}", 1.5 * i as f64))?;
    }
    Ok(())
}

/// Global dot product and norms of v_i = i and w_i = 1 over N entries: Σ i = N(N−1)/2,
/// Σ i² = (N−1)N(2N−1)/6, max = N − 1; a duplicate has the same layout and ghosts.
fn reductions(petsc: &Petsc) -> Result<(), String> {
    let (mut v, ranges, g) = vector(petsc)?;
    let range = ranges[petsc.rank()].clone();
    {
        let mut local = v.local_mut().map_err(|e| e.to_string())?;
        for (k, i) in range.clone().enumerate() {
            local[k] = i as f64;
        }
    }
    let mut w = v.duplicate().map_err(|e| e.to_string())?;
    ensure(w.owned_range() == range && w.ghost_len() == g.len(), "duplicate layout".into())?;
    w.set(1.0).map_err(|e| e.to_string())?;
    let n = v.global_len() as f64;
    let dot = v.dot(&w).map_err(|e| e.to_string())?;
    let norm = v.norm2().map_err(|e| e.to_string())?;
    let norm_max = v.norm_max().map_err(|e| e.to_string())?;
    ensure(dot == n * (n - 1.0) / 2.0, format!("dot {dot}, expected {}", n * (n - 1.0) / 2.0))?;
    let expected = ((n - 1.0) * n * (2.0 * n - 1.0) / 6.0).sqrt();
    ensure((norm - expected).abs() <= 1e-14 * expected, format!("norm {norm}, expected {expected}"))?;
    ensure(norm_max == n - 1.0, format!("max norm {norm_max}"))?;
    // axpy and copy: v − 2·w has Σ = N(N−1)/2 − 2N
    let mut u = v.duplicate().map_err(|e| e.to_string())?;
    u.copy_from(&v).map_err(|e| e.to_string())?;
    u.axpy(-2.0, &w).map_err(|e| e.to_string())?;
    let s = u.dot(&w).map_err(|e| e.to_string())?;
    ensure(s == n * (n - 1.0) / 2.0 - 2.0 * n, format!("Σ(v − 2w) = {s}"))?;
    // the duplicate's ghosts update like the original's
    w.update_ghosts().map_err(|e| e.to_string())?;
    let local = w.local().map_err(|e| e.to_string())?;
    ensure(local.iter().all(|&x| x == 1.0), "duplicate's ghosts after update".into())
}

/// Reductions and broadcasts of rsmpi: Σ r = P(P−1)/2, max P − 1, min 0 over P ranks.
fn collectives(petsc: &Petsc) -> Result<(), String> {
    let (rank, size) = (petsc.rank(), petsc.size());
    let world = petsc.world();
    ensure(sum(world, rank) == size * (size - 1) / 2, "sum of ranks".into())?;
    ensure(sum(world, rank as f64 + 0.5) == (size * size) as f64 / 2.0, "sum of f64".into())?;
    ensure(max(world, rank) == size - 1 && min(world, rank) == 0, "max/min of ranks".into())?;
    ensure(
        max(world, -(rank as f64)) == 0.0 && min(world, -(rank as f64)) == -((size - 1) as f64),
        "max/min f64".into(),
    )?;
    let mut v = vec![rank as f64, 1.0];
    sum_in_place(world, &mut v);
    ensure(v == [(size * (size - 1) / 2) as f64, size as f64], format!("sum_in_place {v:?}"))?;
    let root = size - 1;
    let mut data = if rank == root { vec![0.25, 0.5, root as f64] } else { Vec::new() };
    broadcast(world, root, &mut data);
    ensure(data == [0.25, 0.5, root as f64], format!("broadcast {data:?}"))?;
    let mut bytes = if rank == 0 { b"mesh".to_vec() } else { vec![1; 9] };
    broadcast_bytes(world, 0, &mut bytes);
    ensure(bytes == b"mesh", format!("broadcast bytes {bytes:?}"))
}

/// The bytes rank `r` is sent by the scatter: 10·r + 3 of them (rank 0 none at one rank), each
/// a function of the rank and its position.
fn part_of(r: usize) -> Vec<u8> {
    (0..10 * r + 3).map(|i| (31 * r + 7 * i) as u8).collect()
}

/// The scatter sends each rank its own bytes whole, whether a part is shorter than a piece, a
/// whole number of pieces, or a number and a remainder (pieces of 1, 4 and 13 bytes against
/// parts of 3, 13, 23 … bytes; the part of the last rank, made last, is the longest); the root's
/// `part` is called once per rank, in order.
fn scatter_in_pieces(petsc: &Petsc) -> Result<(), String> {
    let (rank, size) = (petsc.rank(), petsc.size());
    let world = petsc.world();
    for root in [0, size - 1] {
        for chunk in [1, 4, 13] {
            let mut made = Vec::new();
            let got = scatter_bytes_in_chunks(world, root, chunk, |r| {
                made.push(r);
                part_of(r)
            });
            ensure(got == part_of(rank), format!("root {root}, pieces of {chunk}: rank {rank} got {got:?}"))?;
            let expected: Vec<usize> = if rank == root { (0..size).collect() } else { Vec::new() };
            ensure(made == expected, format!("root {root}: parts made {made:?}"))?;
        }
    }
    let got = scatter_bytes(world, 0, part_of);
    ensure(got == part_of(rank), format!("default pieces: rank {rank} got {got:?}"))
}

fn main() -> ExitCode {
    let petsc = Petsc::initialize().expect("MPI and PETSc initialise");
    let cases: [Case; 5] = [
        ("reverse_add_counts_sharers", &reverse_add),
        ("forward_insert_copies_owners", &forward_insert),
        ("dot_and_norms_closed_form", &reductions),
        ("collectives_closed_form", &collectives),
        ("scatter_in_pieces", &scatter_in_pieces),
    ];
    let code = run(&petsc, &cases);
    drop(petsc);
    code
}
