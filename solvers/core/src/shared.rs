//! Arrays that the ranks of one node read from one another directly.
//!
//! With MPI on one node, a [`SharedArray`] lives in an MPI-3 shared-memory
//! window: every rank can read every other rank's array. The flow's pencil
//! transposes then copy each value once, from the array of the rank that
//! holds it into the array of the rank that needs it, instead of packing
//! it, sending it and unpacking it (the shared-memory all-to-all of
//! 2DECOMP&FFT works the same way). Without MPI, or with ranks on several
//! nodes, a shared array is a plain vector and the transposes send
//! messages.
//!
//! Reads of another rank's array are only valid between two
//! [`crate::Communicator::synchronize_shared`] calls during which that
//! rank does not write it; the caller keeps to that. A rank may also write
//! into another rank's array through [`SharedArray::segments_mut`], between
//! two such calls, to parts that no other rank reads or writes meanwhile
//! (the flow's slab solve writes each plane back where it came from).

use std::ops::{Deref, DerefMut};

/// An array of values on this rank, readable by the other ranks of its
/// node when the communicator shares memory.
#[derive(Default)]
pub struct SharedArray {
    storage: Storage,
}

enum Storage {
    Local(Vec<f64>),
    #[cfg(feature = "mpi")]
    Window(window::Window),
}

impl Default for Storage {
    fn default() -> Self {
        Storage::Local(Vec::new())
    }
}

impl SharedArray {
    /// `len` zeros that only this rank reads.
    pub fn local(len: usize) -> Self {
        SharedArray {
            storage: Storage::Local(vec![0.0; len]),
        }
    }

    #[cfg(feature = "mpi")]
    pub(crate) fn window(window: window::Window) -> Self {
        SharedArray {
            storage: Storage::Window(window),
        }
    }

    /// Whether the other ranks can read this array.
    pub fn is_shared(&self) -> bool {
        !matches!(self.storage, Storage::Local(_))
    }

    /// The array of `rank` (this rank's own if the array is not shared).
    pub fn of_rank(&self, rank: usize) -> &[f64] {
        match &self.storage {
            Storage::Local(values) => {
                let _ = rank;
                values
            }
            #[cfg(feature = "mpi")]
            Storage::Window(window) => window.of_rank(rank),
        }
    }

    /// The first value and the length of every rank's array, indexed by
    /// rank (one entry, this rank's, when the array is not shared), for
    /// reads and writes across ranks between two
    /// [`crate::Communicator::synchronize_shared`] calls. The pointers stay
    /// valid while the array lives; the caller keeps every part that one
    /// rank or thread writes apart from what all others read or write
    /// until the next synchronisation, and does not use this rank's array
    /// through `Deref` meanwhile.
    pub fn segments_mut(&mut self) -> Vec<(*mut f64, usize)> {
        match &mut self.storage {
            Storage::Local(values) => vec![(values.as_mut_ptr(), values.len())],
            #[cfg(feature = "mpi")]
            Storage::Window(window) => window.segments().to_vec(),
        }
    }

    #[cfg(feature = "mpi")]
    pub(crate) fn memory_sync(&self) {
        if let Storage::Window(window) = &self.storage {
            window.sync();
        }
    }
}

impl Deref for SharedArray {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        match &self.storage {
            Storage::Local(values) => values,
            #[cfg(feature = "mpi")]
            Storage::Window(window) => window.own(),
        }
    }
}

impl DerefMut for SharedArray {
    fn deref_mut(&mut self) -> &mut [f64] {
        match &mut self.storage {
            Storage::Local(values) => values,
            #[cfg(feature = "mpi")]
            Storage::Window(window) => window.own_mut(),
        }
    }
}

impl std::fmt::Debug for SharedArray {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SharedArray({} values, shared: {})",
            self.len(),
            self.is_shared()
        )
    }
}

/// The MPI-3 shared-memory window behind a shared array.
#[cfg(feature = "mpi")]
pub(crate) mod window {
    use mpi::ffi;
    use mpi::raw::AsRaw;
    use std::os::raw::c_void;
    use std::sync::Arc;

    pub(crate) struct Window {
        window: ffi::MPI_Win,
        /// Every rank's segment: its first value and its length.
        segments: Vec<(*mut f64, usize)>,
        rank: usize,
        /// Keeps the communicator (and MPI) alive as long as the window.
        _world: Arc<crate::communicator::mpi_backend::World>,
    }

    // SAFETY: the window is this process's mapping of the node's shared
    // memory; grainflow drives MPI from one thread at a time (`Serialized`)
    // and a rank writes only its own segment.
    unsafe impl Send for Window {}
    unsafe impl Sync for Window {}

    impl Window {
        /// Collective over `world`, whose ranks all share one node: `len`
        /// zeros on this rank, each rank's segment aligned on its own
        /// pages (`alloc_shared_noncontig`).
        pub(crate) fn allocate(
            world: &Arc<crate::communicator::mpi_backend::World>,
            len: usize,
        ) -> Self {
            use mpi::traits::Communicator as _;
            let comm = world.communicator.as_raw();
            let size = world.communicator.size() as usize;
            let rank = world.communicator.rank() as usize;
            // A segment of at least one value, so that every base is valid.
            let bytes = (len.max(1) * std::mem::size_of::<f64>()) as ffi::MPI_Aint;
            let mut base: *mut f64 = std::ptr::null_mut();
            let mut window: ffi::MPI_Win = unsafe { std::mem::zeroed() };
            // SAFETY: plain MPI-3 calls on a valid communicator; the
            // pointers written are read back as the segments below.
            unsafe {
                let mut info: ffi::MPI_Info = std::mem::zeroed();
                ffi::MPI_Info_create(&mut info);
                ffi::MPI_Info_set(info, c"alloc_shared_noncontig".as_ptr(), c"true".as_ptr());
                ffi::MPI_Win_allocate_shared(
                    bytes,
                    std::mem::size_of::<f64>() as i32,
                    info,
                    comm,
                    &mut base as *mut *mut f64 as *mut c_void,
                    &mut window,
                );
                ffi::MPI_Info_free(&mut info);
                // One passive epoch for the window's life: accesses are
                // ordered by `sync` and the communicator's barriers.
                ffi::MPI_Win_lock_all(ffi::MPI_MODE_NOCHECK as i32, window);
            }
            let segments = (0..size)
                .map(|other| {
                    if other == rank {
                        return (base, len);
                    }
                    let mut bytes: ffi::MPI_Aint = 0;
                    let mut unit: i32 = 0;
                    let mut start: *mut f64 = std::ptr::null_mut();
                    // SAFETY: querying a segment of a live shared window.
                    unsafe {
                        ffi::MPI_Win_shared_query(
                            window,
                            other as i32,
                            &mut bytes,
                            &mut unit,
                            &mut start as *mut *mut f64 as *mut c_void,
                        );
                    }
                    (start, bytes as usize / std::mem::size_of::<f64>())
                })
                .collect();
            let mut window = Window {
                window,
                segments,
                rank,
                _world: world.clone(),
            };
            window.own_mut().fill(0.0);
            window
        }

        pub(crate) fn own(&self) -> &[f64] {
            self.of_rank(self.rank)
        }

        /// Every rank's segment: its first value and its length.
        pub(crate) fn segments(&self) -> &[(*mut f64, usize)] {
            &self.segments
        }

        pub(crate) fn own_mut(&mut self) -> &mut [f64] {
            let (start, len) = self.segments[self.rank];
            // SAFETY: this rank's segment, which other ranks write only
            // between synchronisations that this borrow does not span
            // (see the module's rule).
            unsafe { std::slice::from_raw_parts_mut(start, len) }
        }

        pub(crate) fn of_rank(&self, rank: usize) -> &[f64] {
            let (start, len) = self.segments[rank];
            // SAFETY: a live segment of the window; the caller reads it only
            // while its owner does not write it (see the module's rule).
            unsafe { std::slice::from_raw_parts(start, len) }
        }

        /// Makes this process's stores to the window visible to the others
        /// and theirs to it (with a barrier between two calls).
        pub(crate) fn sync(&self) {
            // SAFETY: a live window in a lock_all epoch.
            unsafe {
                ffi::MPI_Win_sync(self.window);
            }
        }
    }

    impl Drop for Window {
        /// Collective, like the allocation: every rank drops its windows in
        /// the same order (they belong to solvers built in the same order).
        fn drop(&mut self) {
            // SAFETY: the window is live and in the epoch opened above.
            unsafe {
                ffi::MPI_Win_unlock_all(self.window);
                ffi::MPI_Win_free(&mut self.window);
            }
        }
    }
}
