//! HDF5 frames with XDMF 3 time indices (cargo feature `hdf5`), for
//! ParaView and VisIt (through the XDMF index) and for Python (h5py reads
//! the frames directly).
//!
//! - [`FieldFrameH5`]: one file per output time holding cell-centred
//!   fields as global arrays `[nz][ny][nx]` (XDMF's order, x fastest) and
//!   `[nz][ny][nx][3]`, with the grid's face coordinates.
//! - [`ParticleFrameH5`]: one file per output time holding the grains as
//!   arrays `[n]` and `[n][3]`.
//! - [`XdmfIndex`]: `fields.xdmf` / `particles.xdmf`, a temporal collection
//!   of the frames, rewritten whole after each one.
//!
//! On several MPI ranks (cargo feature `mpi` as well, over a parallel HDF5
//! library) every rank writes its share of the one file of a frame through
//! MPI-IO ([`Writers::mpi`]): the file, its datasets and attributes are
//! created by all ranks together (HDF5's collective metadata calls), then
//! every rank writes its own hyperslab of each dataset in one collective
//! transfer (`H5FD_MPIO_COLLECTIVE`; a rank with nothing to write takes
//! part with an empty selection). A frame is written under `NAME.tmp` and
//! renamed once every rank has closed it, as [`crate::write_whole`] does,
//! so a killed run never leaves a frame cut short under its name.
//!
//! Every error comes back as an [`std::io::Error`] naming the file. On
//! several ranks an error on one rank leaves the others in a collective
//! call: the caller stops the job (grainflow's `abort_others`).

mod fields;
mod particles;
mod xdmf;

/// The HDF5 library's bindings the frames are written with, for readers
/// (tests and tools) of the files.
pub use hdf5_metno;

pub use fields::FieldFrameH5;
pub use particles::ParticleFrameH5;
pub use xdmf::{FieldGridDescription, XdmfIndex};

use crate::whole::temporary_path;
use ndarray::{ArrayViewD, IxDyn};
use std::marker::PhantomData;
use std::path::Path;

/// The processes that write a frame together: this process alone, or every
/// rank of an MPI communicator into one shared file (parallel HDF5). Every
/// writer of a frame calls its `write` with the same file name and the same
/// global shapes.
#[derive(Clone, Copy, Default)]
pub struct Writers<'a> {
    #[cfg(feature = "mpi")]
    communicator: Option<&'a mpi::topology::SimpleCommunicator>,
    lifetime: PhantomData<&'a ()>,
}

impl<'a> Writers<'a> {
    /// This process writes the whole frame.
    pub fn serial() -> Self {
        Writers::default()
    }

    /// Every rank of `communicator` writes its share of the frame into one
    /// file through MPI-IO; on one rank this is [`Writers::serial`].
    #[cfg(feature = "mpi")]
    pub fn mpi(communicator: &'a mpi::topology::SimpleCommunicator) -> Self {
        use mpi::traits::Communicator as _;
        Writers {
            communicator: (communicator.size() > 1).then_some(communicator),
            lifetime: PhantomData,
        }
    }

    /// This writer's rank (0 when serial).
    pub fn rank(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(c) = self.communicator {
            use mpi::traits::Communicator as _;
            return c.rank() as usize;
        }
        0
    }

    /// How many processes write the frame.
    pub fn size(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(c) = self.communicator {
            use mpi::traits::Communicator as _;
            return c.size() as usize;
        }
        1
    }

    /// Every writer's `local` count, by rank.
    pub(crate) fn all_counts(&self, local: usize) -> Vec<usize> {
        #[cfg(feature = "mpi")]
        if let Some(c) = self.communicator {
            use mpi::traits::{Communicator as _, CommunicatorCollectives as _};
            let mut counts = vec![0u64; c.size() as usize];
            c.all_gather_into(&(local as u64), &mut counts[..]);
            return counts.into_iter().map(|n| n as usize).collect();
        }
        vec![local]
    }

    /// Whether any writer reports true (so that all return the same error).
    fn any(&self, local: bool) -> bool {
        #[cfg(feature = "mpi")]
        if let Some(c) = self.communicator {
            use mpi::collective::SystemOperation;
            use mpi::traits::CommunicatorCollectives as _;
            let mut any = 0u32;
            c.all_reduce_into(&u32::from(local), &mut any, SystemOperation::max());
            return any > 0;
        }
        local
    }

    /// Writes `block` into `dataset` from the index `start`. On several
    /// ranks every writer calls it for every dataset in the same order (a
    /// collective transfer), those with nothing to write with an empty
    /// block.
    pub(crate) fn write_block<T: hdf5_metno::H5Type>(
        &self,
        dataset: &hdf5_metno::Dataset,
        block: ArrayViewD<'_, T>,
        start: &[usize],
    ) -> hdf5_metno::Result<()> {
        use hdf5_sys::h5d::H5Dwrite;
        use hdf5_sys::h5p::{H5Pclose, H5P_DEFAULT};
        use hdf5_sys::h5s::{H5S_seloper_t, H5Sselect_hyperslab, H5Sselect_none};
        let count = block.shape().to_vec();
        let n = block.len();
        let Some(values) = block.as_slice() else {
            return Err("a block not in C order".into());
        };
        if start.len() != count.len() {
            return Err(format!("a block of {count:?} from {start:?}").into());
        }
        let file_space = dataset.space()?;
        let memory_space = hdf5_metno::Dataspace::try_new(count.clone())?;
        let memory_type = hdf5_metno::Datatype::from_type::<T>()?;
        let start: Vec<u64> = start.iter().map(|&s| s as u64).collect();
        let count: Vec<u64> = count.iter().map(|&c| c as u64).collect();
        let transfer = self.transfer_list()?;
        // SAFETY: every id is open for the call (owned by the handles
        // above or closed below), the selections hold `n` elements each and
        // `values` holds `n` elements of the memory type; HDF5's calls are
        // serialised by hdf5-metno's lock.
        let status = hdf5_metno::sync::sync(|| unsafe {
            let selected = if n == 0 {
                H5Sselect_none(file_space.id()).min(H5Sselect_none(memory_space.id()))
            } else {
                H5Sselect_hyperslab(
                    file_space.id(),
                    H5S_seloper_t::H5S_SELECT_SET,
                    start.as_ptr(),
                    std::ptr::null(),
                    count.as_ptr(),
                    std::ptr::null(),
                )
            };
            let written = if selected < 0 {
                selected
            } else {
                H5Dwrite(
                    dataset.id(),
                    memory_type.id(),
                    memory_space.id(),
                    file_space.id(),
                    transfer.unwrap_or(H5P_DEFAULT),
                    values.as_ptr().cast(),
                )
            };
            if let Some(list) = transfer {
                H5Pclose(list);
            }
            written
        });
        if status < 0 {
            return Err(format!("writing {} ({count:?} from {start:?})", dataset.name()).into());
        }
        Ok(())
    }

    /// A transfer property list of collective MPI-IO on several ranks, or
    /// `None` (HDF5's default) for one process; the caller closes it.
    fn transfer_list(&self) -> hdf5_metno::Result<Option<hdf5_sys::h5i::hid_t>> {
        #[cfg(feature = "mpi")]
        if self.communicator.is_some() {
            use hdf5_sys::h5p::{
                H5FD_mpio_xfer_t, H5Pclose, H5Pcreate, H5Pset_dxpl_mpio, H5P_CLS_DATASET_XFER,
            };
            // SAFETY: the class id is HDF5's (initialised: a file is open);
            // the list is closed here on failure, by the caller otherwise.
            let list = hdf5_metno::sync::sync(|| unsafe {
                let list = H5Pcreate(*H5P_CLS_DATASET_XFER);
                if list >= 0 && H5Pset_dxpl_mpio(list, H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE) < 0 {
                    H5Pclose(list);
                    return -1;
                }
                list
            });
            if list < 0 {
                return Err("a collective MPI-IO transfer list".into());
            }
            return Ok(Some(list));
        }
        Ok(None)
    }

    /// Creates (truncates) `path` for writing by every writer.
    fn create_file(&self, path: &Path) -> hdf5_metno::Result<hdf5_metno::File> {
        #[cfg(feature = "mpi")]
        if let Some(c) = self.communicator {
            use mpi::raw::AsRaw as _;
            return hdf5_metno::File::with_options()
                .with_fapl(|p| p.mpio(c.as_raw(), None))
                .create(path);
        }
        hdf5_metno::File::create(path)
    }
}

impl std::fmt::Debug for Writers<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "rank {} of {} HDF5 writers", self.rank(), self.size())
    }
}

/// `values` as the block of shape `shape` (C order) they must fill.
pub(crate) fn block<'a, T>(
    values: &'a [T],
    shape: &[usize],
) -> hdf5_metno::Result<ArrayViewD<'a, T>> {
    ArrayViewD::from_shape(IxDyn(shape), values)
        .map_err(|e| format!("{} values for a block of {shape:?}: {e}", values.len()).into())
}

/// An [`std::io::Error`] for a failure on `path`.
pub(crate) fn error_on(path: &Path, error: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(format!("{}: {error}", path.display()))
}

/// An invalid argument for the frame `path`.
pub(crate) fn invalid(path: &Path, why: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("{}: {why}", path.display()),
    )
}

/// Checks that an array name can be a dataset and an XDMF attribute.
pub(crate) fn check_name(path: &Path, name: &str) -> std::io::Result<()> {
    let fine = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if fine && name != "grid" {
        Ok(())
    } else {
        Err(invalid(
            path,
            format!("array name {name:?}: use letters, digits, '_', '-' or '.' (not \"grid\")"),
        ))
    }
}

/// Writes the frame `path` whole with every writer: `fill` fills the file
/// created under the temporary sibling, which is renamed over `path` once
/// every writer has closed it. On an error on any writer the temporary is
/// removed and every writer returns an error naming `path`.
pub(crate) fn write_frame(
    path: &Path,
    writers: &Writers,
    fill: impl FnOnce(&hdf5_metno::File) -> hdf5_metno::Result<()>,
) -> std::io::Result<()> {
    let temporary = temporary_path(path);
    let written = writers
        .create_file(&temporary)
        .and_then(|file| {
            fill(&file)?;
            // Closing is collective on several ranks, and flushes.
            file.close()
        })
        .map_err(|e| error_on(path, e));
    let failed = writers.any(written.is_err());
    let root = writers.rank() == 0;
    let renamed = if failed {
        Err(written
            .err()
            .unwrap_or_else(|| error_on(path, "another rank failed to write its share")))
    } else if root {
        std::fs::rename(&temporary, path).map_err(|e| error_on(path, e))
    } else {
        Ok(())
    };
    if root && renamed.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    // The frame is whole under its name on every rank's return.
    let failed = writers.any(renamed.is_err());
    match renamed {
        Err(e) => Err(e),
        Ok(()) if failed => Err(error_on(path, "the root failed to rename the frame")),
        Ok(()) => Ok(()),
    }
}

/// Writes the scalar attribute `name` on `location` (every writer passes
/// the same value).
pub(crate) fn scalar_attribute<T: hdf5_metno::H5Type>(
    location: &hdf5_metno::Location,
    name: &str,
    value: &T,
) -> hdf5_metno::Result<()> {
    location
        .new_attr::<T>()
        .shape(())
        .create(name)?
        .write_scalar(value)
}

/// Writes the string attribute `name` (ASCII, at most 32 bytes) on
/// `location`.
pub(crate) fn text_attribute(
    location: &hdf5_metno::Location,
    name: &str,
    value: &str,
) -> hdf5_metno::Result<()> {
    type Text = hdf5_metno::types::FixedAscii<32>;
    let text = Text::from_ascii(value)
        .map_err(|e| hdf5_metno::Error::from(format!("attribute {name}: {e}")))?;
    scalar_attribute(location, name, &text)
}
