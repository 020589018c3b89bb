//! Collectives on rsmpi communicators: reductions of numbers and arrays, broadcasts of byte and
//! number arrays, [`scatter_bytes`] (each rank its own bytes from one), and [`agree`], the agreement on failure that makes an error on any rank end
//! every rank (never a hang in the next collective).

use crate::error::{Error, Result};
use mpi::collective::SystemOperation;
use mpi::datatype::Equivalence;
use mpi::traits::{Communicator, CommunicatorCollectives, Destination, Root, Source};
use std::fmt::Display;

/// Σ over ranks of `value` (f64, usize, …).
pub fn sum<T: Equivalence + Copy, C: Communicator>(comm: &C, value: T) -> T {
    reduce(comm, value, SystemOperation::sum())
}

/// The maximum over ranks of `value`.
pub fn max<T: Equivalence + Copy, C: Communicator>(comm: &C, value: T) -> T {
    reduce(comm, value, SystemOperation::max())
}

/// The minimum over ranks of `value`.
pub fn min<T: Equivalence + Copy, C: Communicator>(comm: &C, value: T) -> T {
    reduce(comm, value, SystemOperation::min())
}

/// Entrywise Σ over ranks of `values`, in place (the same length on every rank).
pub fn sum_in_place<T: Equivalence + Copy, C: Communicator>(comm: &C, values: &mut [T]) {
    let send = values.to_vec();
    comm.all_reduce_into(&send[..], values, SystemOperation::sum());
}

fn reduce<T: Equivalence + Copy, C: Communicator>(comm: &C, value: T, op: SystemOperation) -> T {
    let mut out = value;
    comm.all_reduce_into(&value, &mut out, op);
    out
}

/// Broadcasts `data` from rank `root`: on return every rank holds root's array (its length too).
pub fn broadcast<T: Equivalence + Copy + Default, C: Communicator>(comm: &C, root: usize, data: &mut Vec<T>) {
    let process = comm.process_at_rank(root as i32);
    let mut len = data.len() as u64;
    process.broadcast_into(&mut len);
    data.resize(len as usize, T::default());
    process.broadcast_into(&mut data[..]);
}

/// Broadcasts bytes (a serialised mesh, a message) from rank `root`.
pub fn broadcast_bytes<C: Communicator>(comm: &C, root: usize, data: &mut Vec<u8>) {
    broadcast(comm, root, data)
}

/// The longest message [`scatter_bytes`] sends (2³⁰ bytes): MPI counts are C `int`s, so a
/// longer part goes in pieces of this size.
pub const SCATTER_CHUNK: usize = 1 << 30;

/// Every rank's own bytes from rank `root` (a rank's part of a problem): on `root`, `part(r)` is
/// made for r = 0, 1, … in turn and sent to rank r before the next is made, so that `root` holds
/// one other rank's part at a time; every rank returns its own (`part` is called on `root` only).
/// Any size: a part goes as its length, then in pieces of at most [`SCATTER_CHUNK`] bytes.
pub fn scatter_bytes<C: Communicator>(comm: &C, root: usize, part: impl FnMut(usize) -> Vec<u8>) -> Vec<u8> {
    scatter_bytes_in_chunks(comm, root, SCATTER_CHUNK, part)
}

/// [`scatter_bytes`] with pieces of at most `chunk` bytes (1 ≤ `chunk` < 2³¹; the same on
/// every rank).
pub fn scatter_bytes_in_chunks<C: Communicator>(
    comm: &C,
    root: usize,
    chunk: usize,
    mut part: impl FnMut(usize) -> Vec<u8>,
) -> Vec<u8> {
    assert!((1..=i32::MAX as usize).contains(&chunk), "scatter_bytes_in_chunks: chunk = {chunk} bytes");
    let from = comm.process_at_rank(root as i32);
    if comm.rank() as usize != root {
        let mut len = 0u64;
        from.receive_into(&mut len);
        let mut bytes = vec![0u8; len as usize];
        // messages between two ranks arrive in the order they were sent
        bytes.chunks_mut(chunk).for_each(|piece| {
            from.receive_into(piece);
        });
        return bytes;
    }
    let mut own = Vec::new();
    for r in 0..comm.size() as usize {
        let bytes = part(r);
        if r == root {
            own = bytes;
        } else {
            let to = comm.process_at_rank(r as i32);
            to.send(&(bytes.len() as u64));
            bytes.chunks(chunk).for_each(|piece| to.send(piece));
        }
    }
    own
}

/// Agreement on failure, to be called by every rank with its own result: all ranks return `Ok`
/// when all succeeded, else all return [`Error::Rank`] with the lowest failing rank's message
/// and the number of failing ranks. Two reductions and a broadcast.
pub fn agree<T, E: Display, C: Communicator>(comm: &C, result: std::result::Result<T, E>) -> Result<T> {
    let size = comm.size() as usize;
    let rank = comm.rank() as usize;
    let failing = min(comm, if result.is_err() { rank } else { size });
    let result = match result {
        // every rank succeeded (a failure here would make `failing` ≤ this rank)
        Ok(value) if failing == size => return Ok(value),
        other => other,
    };
    let failed = sum(comm, usize::from(result.is_err()));
    let mut message = match &result {
        Err(e) if rank == failing => e.to_string().into_bytes(),
        _ => Vec::new(),
    };
    broadcast_bytes(comm, failing, &mut message);
    Err(Error::Rank { rank: failing, failed, size, message: String::from_utf8_lossy(&message).into_owned() })
}
