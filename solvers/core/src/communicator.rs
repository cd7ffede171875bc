//! The communicator: global reductions, the exchanges of the domain
//! decomposition, and the rank layout.
//!
//! The serial communicator is a single rank: its reductions return the local
//! value and its exchanges are copies to itself. With the cargo feature `mpi`
//! the same calls go through MPI (rsmpi). Solvers only use these calls, so
//! one code path serves 1 and N ranks.
//!
//! MPI is initialised with the `Serialized` threading level: grainflow calls
//! it from the thread that runs the time loop, never from inside a parallel
//! loop, so calls never overlap.

use crate::shared::SharedArray;

/// A group of ranks sharing one scene.
#[derive(Clone, Debug)]
pub struct Communicator {
    rank: usize,
    size: usize,
    /// Whether arrays may be shared among ranks of one node
    /// ([`Communicator::shares_memory`]).
    memory_sharing: bool,
    #[cfg(feature = "mpi")]
    world: Option<std::sync::Arc<mpi_backend::World>>,
}

impl Communicator {
    /// One rank owning the whole domain.
    pub fn serial() -> Self {
        Communicator {
            rank: 0,
            size: 1,
            memory_sharing: false,
            #[cfg(feature = "mpi")]
            world: None,
        }
    }

    /// Every rank of the MPI job (`MPI_COMM_WORLD`). MPI must have been
    /// initialised (see [`mpi_backend::initialize`]).
    #[cfg(feature = "mpi")]
    pub fn world(world: mpi::topology::SimpleCommunicator) -> Self {
        use mpi::traits::Communicator as _;
        let rank = world.rank() as usize;
        let size = world.size() as usize;
        // Ranks that all live on one node can read one another's memory.
        let node_size = world.split_shared(rank as i32).size() as usize;
        Communicator {
            rank,
            size,
            memory_sharing: true,
            world: Some(std::sync::Arc::new(mpi_backend::World {
                communicator: world,
                one_node: node_size == size,
            })),
        }
    }

    /// The MPI communicator of the ranks (None for the serial one), for
    /// libraries that take one themselves, e.g. parallel HDF5.
    #[cfg(feature = "mpi")]
    pub fn mpi(&self) -> Option<&mpi::topology::SimpleCommunicator> {
        self.world.as_ref().map(|world| &world.communicator)
    }

    pub fn rank(&self) -> usize {
        self.rank
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// Whether this rank writes the shared outputs (log, series, summary).
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// Sum of a value over all ranks.
    pub fn sum(&self, local: f64) -> f64 {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.sum(local);
        }
        local
    }

    /// Sum of a count over all ranks.
    pub fn sum_count(&self, local: usize) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.sum_count(local as u64) as usize;
        }
        local
    }

    /// Maximum of a value over all ranks.
    pub fn max(&self, local: f64) -> f64 {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.max(local);
        }
        local
    }

    /// Whether any rank reports true.
    pub fn any(&self, local: bool) -> bool {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.sum_count(u64::from(local)) > 0;
        }
        local
    }

    /// One stage of a neighbour exchange: sends `outgoing` to rank
    /// `destination` and returns what rank `source` sent (empty without a
    /// source). Every rank calls it with the same `stage` number; a rank
    /// that is its own neighbour (a periodic axis of one rank) copies.
    pub fn shift(
        &self,
        stage: u16,
        outgoing: &[f64],
        destination: Option<usize>,
        source: Option<usize>,
    ) -> Vec<f64> {
        let to_self = destination == Some(self.rank);
        let from_self = source == Some(self.rank);
        assert_eq!(
            to_self, from_self,
            "a rank that sends to itself must also receive from itself"
        );
        if to_self {
            return outgoing.to_vec();
        }
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.shift(stage, outgoing, destination, source);
        }
        let _ = stage;
        assert!(
            destination.is_none() && source.is_none(),
            "the serial communicator has no other rank"
        );
        Vec::new()
    }

    /// Sends `outgoing[r]` to every rank r and returns what each rank sent
    /// here, indexed by sender (`outgoing.len()` must be the number of ranks).
    pub fn exchange(&self, outgoing: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        assert_eq!(outgoing.len(), self.size, "one message per rank");
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.exchange(&outgoing);
        }
        outgoing
    }

    /// An all-to-all where every rank already knows how many numbers each
    /// other sends it, between flat buffers the caller keeps: `send` holds
    /// the messages to ranks 0, 1, … one after the other (`send_counts[r]`
    /// numbers for rank r), `receive` gets those from ranks 0, 1, …
    /// (`receive_counts[r]` from rank r).
    /// Nothing is allocated: for the large, repeated transposes of the
    /// flow's direct solves.
    pub fn all_to_all_flat(
        &self,
        send: &[f64],
        send_counts: &[usize],
        receive: &mut [f64],
        receive_counts: &[usize],
    ) {
        assert_eq!(send_counts.iter().sum::<usize>(), send.len());
        assert_eq!(receive_counts.iter().sum::<usize>(), receive.len());
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.all_to_all_flat(send, send_counts, receive, receive_counts);
        }
        receive.copy_from_slice(send);
    }

    /// Element-wise sum of `values` over all ranks, in place (every rank
    /// passes as many).
    pub fn sum_each(&self, values: &mut [f64]) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            world.sum_each(values);
        }
        let _ = values;
    }

    /// Overwrites `values` on every rank with the `root` rank's (every rank
    /// passes as many).
    pub fn broadcast(&self, root: usize, values: &mut [f64]) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            world.broadcast(root, values);
        }
        let _ = (root, values);
    }

    /// Whether every rank can read the others' [`SharedArray`]s: MPI ranks
    /// that all run on one node (a single rank reads only its own).
    pub fn shares_memory(&self) -> bool {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return self.memory_sharing && world.one_node && self.size > 1;
        }
        false
    }

    /// The same ranks, sharing memory on one node only if `allowed` (else
    /// every exchange is a message, as between nodes).
    pub fn with_shared_memory(mut self, allowed: bool) -> Self {
        self.memory_sharing = allowed;
        self
    }

    /// `len` zeros on this rank that the other ranks can read when they
    /// share memory ([`Communicator::shares_memory`]); a plain array
    /// otherwise. Collective: every rank allocates its arrays in the same
    /// order (and frees them in the same order).
    pub fn shared_array(&self, len: usize) -> SharedArray {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            if self.shares_memory() {
                return SharedArray::window(crate::shared::window::Window::allocate(world, len));
            }
        }
        SharedArray::local(len)
    }

    /// Collective: after it, what every rank wrote to its shared `arrays`
    /// before it is visible to all, and every rank has finished what it did
    /// before it (in particular reading the others' arrays).
    pub fn synchronize_shared(&self, arrays: &[&SharedArray]) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            arrays.iter().for_each(|array| array.memory_sync());
            world.barrier();
            arrays.iter().for_each(|array| array.memory_sync());
        }
        let _ = arrays;
    }

    /// Returns once every rank has called it: what each rank did before is
    /// done on all (e.g. the pieces of an output are written before the
    /// root's index lists them).
    pub fn barrier(&self) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            world.barrier();
        }
    }

    /// Collects every rank's `local` on the root, indexed by rank (None on
    /// the other ranks).
    pub fn gather(&self, local: &[f64]) -> Option<Vec<Vec<f64>>> {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            return world.gather(local);
        }
        Some(vec![local.to_vec()])
    }

    /// Stops every rank of the job after printing `message` (a failure on
    /// one rank must not leave the others waiting in a collective call).
    /// On one rank it returns, so the caller reports the error itself.
    pub fn abort_others(&self, message: &str) {
        #[cfg(feature = "mpi")]
        if let Some(world) = &self.world {
            if self.size > 1 {
                eprintln!("error on rank {} of {}: {message}", self.rank, self.size);
                eprintln!("stopping all ranks");
                world.abort(1);
            }
        }
        let _ = message;
    }
}

/// The MPI side of [`Communicator`].
#[cfg(feature = "mpi")]
pub mod mpi_backend {
    use mpi::collective::SystemOperation;
    use mpi::datatype::{Partition, PartitionMut};
    use mpi::traits::*;
    use mpi::Count;

    /// `MPI_COMM_WORLD`, shareable between threads: grainflow serialises
    /// its MPI calls (one thread drives the time loop), which the
    /// `Serialized` threading level allows.
    pub struct World {
        pub communicator: mpi::topology::SimpleCommunicator,
        /// Whether all ranks share one node's memory.
        pub one_node: bool,
    }

    // SAFETY: MPI is initialised with `Threading::Serialized` (see
    // `initialize`), which allows calls from any thread as long as they do
    // not overlap; grainflow makes them only from the time-loop thread.
    unsafe impl Send for World {}
    unsafe impl Sync for World {}

    impl std::fmt::Debug for World {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "MPI world of {} ranks", self.communicator.size())
        }
    }

    /// Initialises MPI for grainflow; the universe finalises MPI when dropped.
    pub fn initialize() -> Option<mpi::environment::Universe> {
        let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Serialized)?;
        Some(universe)
    }

    impl World {
        pub fn sum(&self, local: f64) -> f64 {
            let mut total = 0.0;
            self.communicator
                .all_reduce_into(&local, &mut total, SystemOperation::sum());
            total
        }

        pub fn sum_each(&self, values: &mut [f64]) {
            let local = values.to_vec();
            self.communicator
                .all_reduce_into(&local[..], values, SystemOperation::sum());
        }

        pub fn broadcast(&self, root: usize, values: &mut [f64]) {
            self.communicator
                .process_at_rank(root as i32)
                .broadcast_into(values);
        }

        pub fn sum_count(&self, local: u64) -> u64 {
            let mut total = 0u64;
            self.communicator
                .all_reduce_into(&local, &mut total, SystemOperation::sum());
            total
        }

        pub fn max(&self, local: f64) -> f64 {
            let mut largest = 0.0;
            self.communicator
                .all_reduce_into(&local, &mut largest, SystemOperation::max());
            largest
        }

        pub fn shift(
            &self,
            stage: u16,
            outgoing: &[f64],
            destination: Option<usize>,
            source: Option<usize>,
        ) -> Vec<f64> {
            let tag = i32::from(stage);
            mpi::request::scope(|scope| {
                let sent = destination.map(|rank| {
                    self.communicator
                        .process_at_rank(rank as i32)
                        .immediate_send_with_tag(scope, outgoing, tag)
                });
                let received = source.map(|rank| {
                    self.communicator
                        .process_at_rank(rank as i32)
                        .receive_vec_with_tag::<f64>(tag)
                        .0
                });
                if let Some(request) = sent {
                    request.wait();
                }
                received.unwrap_or_default()
            })
        }

        pub fn exchange(&self, outgoing: &[Vec<f64>]) -> Vec<Vec<f64>> {
            let send_counts: Vec<Count> = outgoing.iter().map(|m| m.len() as Count).collect();
            let mut receive_counts = vec![0 as Count; outgoing.len()];
            self.communicator
                .all_to_all_into(&send_counts[..], &mut receive_counts[..]);
            let incoming: Vec<usize> = receive_counts.iter().map(|&c| c as usize).collect();
            self.exchange_known(outgoing, &incoming)
        }

        pub fn exchange_known(&self, outgoing: &[Vec<f64>], incoming: &[usize]) -> Vec<Vec<f64>> {
            let send_counts: Vec<usize> = outgoing.iter().map(Vec::len).collect();
            let mut received = vec![0.0; incoming.iter().sum()];
            self.all_to_all_flat(&outgoing.concat(), &send_counts, &mut received, incoming);
            let mut rest = &received[..];
            incoming
                .iter()
                .map(|&count| {
                    let (message, tail) = rest.split_at(count);
                    rest = tail;
                    message.to_vec()
                })
                .collect()
        }

        pub fn all_to_all_flat(
            &self,
            send: &[f64],
            send_counts: &[usize],
            receive: &mut [f64],
            receive_counts: &[usize],
        ) {
            let send_counts: Vec<Count> = send_counts.iter().map(|&c| c as Count).collect();
            let receive_counts: Vec<Count> = receive_counts.iter().map(|&c| c as Count).collect();
            let send_displs = displacements(&send_counts);
            let receive_displs = displacements(&receive_counts);
            let send = Partition::new(send, &send_counts[..], &send_displs[..]);
            let mut receive = PartitionMut::new(receive, &receive_counts[..], &receive_displs[..]);
            self.communicator
                .all_to_all_varcount_into(&send, &mut receive);
        }

        pub fn gather(&self, local: &[f64]) -> Option<Vec<Vec<f64>>> {
            let root = self.communicator.process_at_rank(0);
            let count = local.len() as Count;
            if self.communicator.rank() != 0 {
                root.gather_into(&count);
                root.gather_varcount_into(local);
                return None;
            }
            let mut counts = vec![0 as Count; self.communicator.size() as usize];
            root.gather_into_root(&count, &mut counts[..]);
            let displs = displacements(&counts);
            let total: usize = counts.iter().map(|&c| c as usize).sum();
            let mut received = vec![0.0; total];
            {
                let mut receive = PartitionMut::new(&mut received[..], &counts[..], &displs[..]);
                root.gather_varcount_into_root(local, &mut receive);
            }
            Some(split(&received, &counts, &displs))
        }

        pub fn barrier(&self) {
            self.communicator.barrier();
        }

        pub fn abort(&self, code: i32) -> ! {
            self.communicator.abort(code)
        }
    }

    fn displacements(counts: &[Count]) -> Vec<Count> {
        counts
            .iter()
            .scan(0, |offset, &c| {
                let start = *offset;
                *offset += c;
                Some(start)
            })
            .collect()
    }

    fn split(flat: &[f64], counts: &[Count], displs: &[Count]) -> Vec<Vec<f64>> {
        counts
            .iter()
            .zip(displs)
            .map(|(&c, &d)| flat[d as usize..(d + c) as usize].to_vec())
            .collect()
    }
}
