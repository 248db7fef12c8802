//! Per-message costs of the operations the distributed step uses (docs/distributed.md, "Cost
//! model"): the personalised exchange with known sizes (`MPI_Alltoallv`, once per sweep and
//! direction) for several payloads, the exchange with unknown sizes (`MPI_Alltoall` of the
//! counts + `MPI_Alltoallv`, the fallback of the migration) and their point-to-point
//! replacements with the slab neighbours (`MPI_Isend`/`MPI_Irecv`, what the step uses since
//! #44), and the reduction of 4 doubles (`MPI_Allreduce`, twice per sweep). Medians over
//! repetitions, in µs.
//!
//!     cargo build --release --features coulomb-cli/mpi --examples
//!     mpirun -np 2 target/release/examples/mpi_costs

use coulomb_granular::distributed::{mpi, Comm};
use std::time::Instant;

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

fn main() {
    let Some(universe) = mpi::initialize() else {
        eprintln!("MPI could not be initialized");
        std::process::exit(1);
    };
    let mut comm = Comm::new(universe.world());
    let (rank, size) = (comm.rank(), comm.size());
    let reps = 2000;
    let mut report = Vec::new();
    for words in [6usize, 60, 600, 6000, 60000] {
        // each rank sends `words` doubles to its slab neighbours (rank ± 1), nothing to others
        let send: Vec<Vec<f64>> = (0..size)
            .map(|r| {
                if r + 1 == rank || r == rank + 1 {
                    vec![1.0; words]
                } else {
                    Vec::new()
                }
            })
            .collect();
        let lens: Vec<usize> = send.iter().map(Vec::len).collect();
        let mut t = Vec::with_capacity(reps);
        for _ in 0..reps / 10 + 10 {
            comm.barrier();
            let s = Instant::now();
            let _ = comm.exchange_known(&send, &lens);
            t.push(s.elapsed().as_secs_f64() * 1e6);
        }
        report.push((
            format!("alltoallv, {} bytes to each neighbour", 8 * words),
            median(t),
        ));
        // the same payloads point to point with the neighbours (Isend/Irecv, the ghost
        // exchanges of the step)
        let peers: Vec<usize> = (0..size)
            .filter(|&r| r + 1 == rank || r == rank + 1)
            .collect();
        let mut t = Vec::with_capacity(reps);
        for _ in 0..reps / 10 + 10 {
            comm.barrier();
            let s = Instant::now();
            let _ = comm.exchange_peers_known(&peers, &send, &lens);
            t.push(s.elapsed().as_secs_f64() * 1e6);
        }
        report.push((
            format!("isend/irecv, {} bytes to each neighbour", 8 * words),
            median(t),
        ));
    }
    let send: Vec<Vec<f64>> = (0..size).map(|_| vec![1.0; 60]).collect();
    let mut t = Vec::new();
    for _ in 0..reps / 10 {
        comm.barrier();
        let s = Instant::now();
        let _ = comm.exchange(&send);
        t.push(s.elapsed().as_secs_f64() * 1e6);
    }
    report.push(("alltoall counts + alltoallv, 480 bytes".into(), median(t)));
    let peers: Vec<usize> = (0..size)
        .filter(|&r| r + 1 == rank || r == rank + 1)
        .collect();
    let send: Vec<Vec<f64>> = (0..size)
        .map(|r| {
            if peers.contains(&r) {
                vec![1.0; 60]
            } else {
                Vec::new()
            }
        })
        .collect();
    let mut t = Vec::new();
    for _ in 0..reps / 10 {
        comm.barrier();
        let s = Instant::now();
        let _ = comm.exchange_peers(&peers, &send);
        t.push(s.elapsed().as_secs_f64() * 1e6);
    }
    report.push((
        "isend/irecv sizes + data with the neighbours, 480 bytes".into(),
        median(t),
    ));
    let mut t = Vec::new();
    for _ in 0..reps {
        comm.barrier();
        let mut x = [1.0, 2.0, 3.0, 4.0];
        let s = Instant::now();
        comm.sum(&mut x);
        t.push(s.elapsed().as_secs_f64() * 1e6);
    }
    report.push(("allreduce of 4 doubles".into(), median(t)));
    if rank == 0 {
        println!("{size} ranks");
        for (what, us) in report {
            println!("{us:>10.2} µs  {what}");
        }
    }
}
