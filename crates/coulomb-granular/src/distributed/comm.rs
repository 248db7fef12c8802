//! The few MPI operations the distributed step uses, on `f64` buffers, each timed so that the
//! communication time of a step can be reported ([`Comm::seconds`]): point-to-point
//! exchanges with given peers (nonblocking sends and receives), the personalised all-to-all
//! exchange (migration beyond the adjacent slabs, gathering) and reductions.

use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;
use std::time::Instant;

/// A communicator with timing: every call adds its wall-clock time and one message count per
/// peer actually addressed (nonzero count) to the running totals.
pub struct Comm {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    seconds: f64,
    messages: u64,
    bytes: u64,
}

impl std::fmt::Debug for Comm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Comm")
            .field("rank", &self.rank)
            .field("size", &self.size)
            .field("seconds", &self.seconds)
            .finish()
    }
}

impl Comm {
    /// Wraps an MPI communicator (usually `universe.world()`).
    pub fn new(world: SimpleCommunicator) -> Self {
        let rank = usize::try_from(world.rank()).unwrap_or(0);
        let size = usize::try_from(world.size()).unwrap_or(1).max(1);
        Self {
            world,
            rank,
            size,
            seconds: 0.0,
            messages: 0,
            bytes: 0,
        }
    }
    /// This process's rank.
    pub fn rank(&self) -> usize {
        self.rank
    }
    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.size
    }
    /// Seconds spent in communication so far.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }
    /// Point-to-point messages (nonempty peer buffers) and collectives started so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }
    /// Bytes sent so far.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Personalised exchange: `send[r]` goes to rank r; returns what each rank sent here.
    /// The counts are exchanged first (one `MPI_Alltoall`), then the data (`MPI_Alltoallv`).
    pub fn exchange(&mut self, send: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let t = Instant::now();
        let counts: Vec<Count> = send.iter().map(|b| count(b.len())).collect();
        let mut recv_counts: Vec<Count> = vec![0; self.size];
        self.world
            .all_to_all_into(&counts[..], &mut recv_counts[..]);
        let out = self.exchange_counted(send, &recv_counts);
        self.seconds += t.elapsed().as_secs_f64();
        out
    }

    /// Personalised exchange whose receive sizes are known (`recv_len[r]` values from rank r):
    /// one `MPI_Alltoallv`.
    pub fn exchange_known(&mut self, send: &[Vec<f64>], recv_len: &[usize]) -> Vec<Vec<f64>> {
        let t = Instant::now();
        let counts: Vec<Count> = recv_len.iter().map(|&n| count(n)).collect();
        let out = self.exchange_counted(send, &counts);
        self.seconds += t.elapsed().as_secs_f64();
        out
    }

    fn exchange_counted(&mut self, send: &[Vec<f64>], recv_counts: &[Count]) -> Vec<Vec<f64>> {
        let send_counts: Vec<Count> = send.iter().map(|b| count(b.len())).collect();
        let send_displs = displacements(&send_counts);
        let recv_displs = displacements(recv_counts);
        let flat: Vec<f64> = send.iter().flatten().copied().collect();
        let total: usize = recv_counts.iter().map(|&c| c.max(0) as usize).sum();
        let mut buf = vec![0.0f64; total];
        {
            let s = Partition::new(&flat[..], &send_counts[..], &send_displs[..]);
            let mut r = PartitionMut::new(&mut buf[..], recv_counts, &recv_displs[..]);
            self.world.all_to_all_varcount_into(&s, &mut r);
        }
        self.messages += send_counts.iter().filter(|&&c| c > 0).count() as u64;
        self.bytes += 8 * flat.len() as u64;
        recv_counts
            .iter()
            .zip(&recv_displs)
            .map(|(&c, &d)| buf[d as usize..(d + c) as usize].to_vec())
            .collect()
    }

    /// Point-to-point exchange with the ranks `peers` (each of which lists this rank among its
    /// own peers): `send[r]` goes to rank r (empty for a rank not in `peers`); returns what
    /// each rank sent here (empty from the others). The sizes go first, one word each way per
    /// peer, then the nonempty buffers; every send and receive is nonblocking
    /// (`MPI_Isend`/`MPI_Irecv`), all posted before any is waited for.
    pub fn exchange_peers(&mut self, peers: &[usize], send: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let t = Instant::now();
        let out: Vec<u64> = peers.iter().map(|&p| send[p].len() as u64).collect();
        let mut got = vec![0u64; peers.len()];
        let world = &self.world;
        mpi::request::scope(|scope| {
            let mut pending = Vec::with_capacity(2 * peers.len());
            for (&p, n) in peers.iter().zip(got.iter_mut()) {
                let from = world.process_at_rank(rank_of(p));
                pending.push(from.immediate_receive_into_with_tag(scope, n, SIZE_TAG));
            }
            for (&p, n) in peers.iter().zip(&out) {
                let to = world.process_at_rank(rank_of(p));
                pending.push(to.immediate_send_with_tag(scope, n, SIZE_TAG));
            }
            for r in pending {
                r.wait();
            }
        });
        self.messages += 2 * peers.len() as u64;
        self.bytes += 8 * peers.len() as u64;
        let mut recv_len = vec![0usize; self.size];
        for (&p, &n) in peers.iter().zip(&got) {
            recv_len[p] = usize::try_from(n).unwrap_or(usize::MAX);
        }
        let out = self.peers_counted(peers, send, &recv_len);
        self.seconds += t.elapsed().as_secs_f64();
        out
    }

    /// Point-to-point exchange with the ranks `peers` whose receive sizes are known
    /// (`recv_len[r]` values from rank r, 0 for a rank not in `peers`): the nonempty buffers
    /// only, nonblocking as [`Self::exchange_peers`].
    pub fn exchange_peers_known(
        &mut self,
        peers: &[usize],
        send: &[Vec<f64>],
        recv_len: &[usize],
    ) -> Vec<Vec<f64>> {
        let t = Instant::now();
        let out = self.peers_counted(peers, send, recv_len);
        self.seconds += t.elapsed().as_secs_f64();
        out
    }

    fn peers_counted(
        &mut self,
        peers: &[usize],
        send: &[Vec<f64>],
        recv_len: &[usize],
    ) -> Vec<Vec<f64>> {
        let mut recv: Vec<Vec<f64>> = vec![Vec::new(); self.size];
        for &p in peers {
            recv[p] = vec![0.0; recv_len[p]];
        }
        let world = &self.world;
        let (mut messages, mut bytes) = (0u64, 0u64);
        mpi::request::scope(|scope| {
            let mut pending = Vec::with_capacity(2 * peers.len());
            for (p, buf) in recv.iter_mut().enumerate() {
                if !buf.is_empty() {
                    let from = world.process_at_rank(rank_of(p));
                    pending.push(from.immediate_receive_into_with_tag(
                        scope,
                        &mut buf[..],
                        DATA_TAG,
                    ));
                }
            }
            for &p in peers {
                if !send[p].is_empty() {
                    let to = world.process_at_rank(rank_of(p));
                    pending.push(to.immediate_send_with_tag(scope, &send[p][..], DATA_TAG));
                    messages += 1;
                    bytes += 8 * send[p].len() as u64;
                }
            }
            for r in pending {
                r.wait();
            }
        });
        self.messages += messages;
        self.bytes += bytes;
        recv
    }

    /// Element-wise sum over the ranks, in place.
    pub fn sum(&mut self, x: &mut [f64]) {
        self.reduce(x, SystemOperation::sum());
    }
    /// Element-wise maximum over the ranks, in place.
    pub fn max(&mut self, x: &mut [f64]) {
        self.reduce(x, SystemOperation::max());
    }
    fn reduce(&mut self, x: &mut [f64], op: SystemOperation) {
        let t = Instant::now();
        let local = x.to_vec();
        self.world.all_reduce_into(&local[..], x, op);
        self.messages += 1;
        self.bytes += 8 * x.len() as u64;
        self.seconds += t.elapsed().as_secs_f64();
    }
    /// Waits for every rank.
    pub fn barrier(&self) {
        self.world.barrier();
    }
}

/// Tag of the size messages of [`Comm::exchange_peers`].
const SIZE_TAG: mpi::Tag = 1;
/// Tag of the data messages of the point-to-point exchanges.
const DATA_TAG: mpi::Tag = 2;

/// The MPI rank of rank index `r` (ranks are below 2³¹: `MPI_Comm_size` is an int).
fn rank_of(r: usize) -> mpi::Rank {
    mpi::Rank::try_from(r).unwrap_or(mpi::Rank::MAX)
}

/// An MPI count (buffers here are far below 2³¹ entries; larger ones saturate and the
/// partition check of rsmpi refuses them instead of wrapping).
fn count(n: usize) -> Count {
    Count::try_from(n).unwrap_or(Count::MAX)
}

fn displacements(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0 as Count, |acc, &c| {
            let d = *acc;
            *acc = acc.saturating_add(c);
            Some(d)
        })
        .collect()
}
