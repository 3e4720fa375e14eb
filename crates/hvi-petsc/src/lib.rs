//! A small safe wrapper over the PETSc calls hvi needs (docs/method.md §13 of hvi): the
//! library's lifetime tied to MPI's ([`Petsc`]), a distributed sparse matrix ([`Matrix`],
//! MPIAIJ with preallocation), vectors ([`Vector`]; [`Scatter`] moves chosen entries between
//! ranks, [`AllGather`] all of them to every rank), dense blocks of right-hand sides
//! ([`DenseBlock`]), a linear solver ([`Solver`]: MUMPS Cholesky or CG with GAMG;
//! `KSPMatSolve` for many right-hand sides) and MUMPS's memory estimates ([`MumpsMemory`]).
//!
//! Every `PetscErrorCode` becomes an [`Error`] carrying PETSc's own message (an error handler
//! records it instead of printing a traceback); nothing here panics across the FFI boundary.
//! PETSc objects are collective: every call that the PETSc manual calls collective must be made
//! on every rank, in the same order. The objects are not thread-safe; they are `Send` so that a
//! caller may keep them behind a mutex.

pub mod ffi;

pub use mpi;

use mpi::topology::{Communicator, SimpleCommunicator};
use std::ffi::{CStr, CString};
use std::fmt;
use std::ptr;
use std::sync::{Arc, Mutex};

/// PETSc's global index type (32-bit in Debian's build).
pub type Int = ffi::PetscInt;

/// A failed PETSc call: its error code and PETSc's message.
#[derive(Clone, Debug)]
pub struct Error {
    pub code: i32,
    pub message: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "PETSc error {}: {}", self.code, self.message)
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;

/// The first message of the error being raised (PETSc calls the handler once where the error
/// starts and again in every caller on the way up).
static LAST_ERROR: Mutex<Option<String>> = Mutex::new(None);

unsafe extern "C" fn record_error(
    _comm: ffi::MPI_Comm,
    line: std::os::raw::c_int,
    function: *const std::os::raw::c_char,
    file: *const std::os::raw::c_char,
    code: ffi::PetscErrorCode,
    kind: ffi::PetscErrorType,
    message: *const std::os::raw::c_char,
    _ctx: *mut std::os::raw::c_void,
) -> ffi::PetscErrorCode {
    if kind == ffi::PetscErrorType::PETSC_ERROR_INITIAL {
        let text = |p: *const std::os::raw::c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: PETSc passes NUL-terminated strings (or null).
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let (function, file, message) = (text(function), text(file), text(message));
        if let Ok(mut last) = LAST_ERROR.lock() {
            *last = Some(format!("{} (in {function}, {file}:{line})", message.trim()));
        }
    }
    code
}

/// Turns a PETSc return code into a result, with the message the error handler recorded.
fn check(code: ffi::PetscErrorCode) -> Result<()> {
    if code == 0 {
        return Ok(());
    }
    let recorded = LAST_ERROR.lock().ok().and_then(|mut l| l.take());
    let message = recorded.unwrap_or_else(|| {
        let mut text: *const std::os::raw::c_char = ptr::null();
        // SAFETY: PetscErrorMessage writes a pointer to a static string.
        unsafe { ffi::PetscErrorMessage(code, &mut text, ptr::null_mut()) };
        if text.is_null() {
            "unknown error".into()
        } else {
            // SAFETY: a static NUL-terminated string.
            unsafe { CStr::from_ptr(text) }.to_string_lossy().into_owned()
        }
    });
    Err(Error { code, message })
}

fn error(message: impl Into<String>) -> Error {
    Error {
        code: -1,
        message: message.into(),
    }
}

fn int(v: usize, what: &str) -> Result<Int> {
    Int::try_from(v).map_err(|_| {
        error(format!(
            "{what} = {v} exceeds PETSc's 32-bit index range (build PETSc with 64-bit indices)"
        ))
    })
}

/// PETSc initialised over MPI; finalised (then MPI) when the last object holding it is
/// dropped. One per process.
pub struct Petsc {
    world: SimpleCommunicator,
    session: Arc<Session>,
}

/// What every PETSc object holds: PETSc stays initialised while one exists.
struct Session {
    // Dropped after PetscFinalize (in `Drop`): MPI outlives PETSc.
    _universe: mpi::environment::Universe,
}

// SAFETY: the session is only created and dropped; PETSc's finalisation is not tied to a thread.
unsafe impl Send for Session {}
unsafe impl Sync for Session {}

impl Drop for Session {
    fn drop(&mut self) {
        // SAFETY: every PETSc object holds the session, so all are destroyed by now.
        unsafe {
            ffi::PetscFinalize();
        }
    }
}

impl Petsc {
    /// Initialises MPI and PETSc. `options` are set in PETSc's options database before any
    /// object is created (the `PETSC_OPTIONS` environment variable is read as usual and may
    /// override them).
    pub fn init(options: &[(&str, &str)]) -> Result<Petsc> {
        let universe = mpi::initialize().ok_or_else(|| error("MPI was already initialised in this process"))?;
        // SAFETY: argc/argv may be null; PETSc then reads options from PETSC_OPTIONS only.
        check(unsafe { ffi::PetscInitialize(ptr::null_mut(), ptr::null_mut(), ptr::null(), ptr::null()) })?;
        // SAFETY: the handler is a plain function that never unwinds.
        check(unsafe { ffi::PetscPushErrorHandler(Some(record_error), ptr::null_mut()) })?;
        for (key, value) in options {
            let (k, v) = (cstring(key)?, cstring(value)?);
            // SAFETY: NUL-terminated strings; null means the global options database.
            check(unsafe { ffi::PetscOptionsSetValue(ptr::null_mut(), k.as_ptr(), v.as_ptr()) })?;
        }
        let world = universe.world();
        Ok(Petsc {
            world,
            session: Arc::new(Session { _universe: universe }),
        })
    }

    /// MPI_COMM_WORLD (PETSc's PETSC_COMM_WORLD).
    pub fn world(&self) -> &SimpleCommunicator {
        &self.world
    }

    pub fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    pub fn size(&self) -> usize {
        self.world.size() as usize
    }
}

fn cstring(s: &str) -> Result<CString> {
    CString::new(s).map_err(|_| error(format!("option `{s}` contains a NUL byte")))
}

fn comm() -> ffi::MPI_Comm {
    // SAFETY: PETSC_COMM_WORLD is set by PetscInitialize and never changed afterwards.
    unsafe { ffi::PETSC_COMM_WORLD }
}

/// MPI_COMM_SELF (PETSc's PETSC_COMM_SELF is a macro bindgen cannot translate): the handle of
/// the MPI that PETSc was built with, as rsmpi links it.
fn comm_self() -> ffi::MPI_Comm {
    use mpi::raw::AsRaw;
    // The same MPI library (pkg-config's) on both sides: the handles are the same pointer.
    SimpleCommunicator::self_comm().as_raw().0.cast()
}

/// A distributed vector.
pub struct Vector {
    raw: ffi::Vec,
    _session: Arc<Session>,
}

// SAFETY: PETSc objects are not tied to a thread; callers serialise access (a &mut or a mutex).
unsafe impl Send for Vector {}

impl Vector {
    /// A distributed vector with `local` entries on this rank, zero (collective).
    pub fn mpi(petsc: &Petsc, local: usize) -> Result<Vector> {
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::VecCreateMPI(comm(), int(local, "local entries")?, ffi::PETSC_DETERMINE, &mut raw) })?;
        let mut v = Vector {
            raw,
            _session: petsc.session.clone(),
        };
        v.with_local_mut(|a| a.fill(0.0))?;
        Ok(v)
    }

    /// Sets the locally owned entries to `values` (as many as this rank owns).
    pub fn set_local(&mut self, values: &[f64]) -> Result<()> {
        let mut wrong = None;
        self.with_local_mut(|a| match a.len() == values.len() {
            true => a.copy_from_slice(values),
            false => wrong = Some(a.len()),
        })?;
        match wrong {
            None => Ok(()),
            Some(n) => Err(error(format!(
                "{} values for the {n} entries this rank owns",
                values.len()
            ))),
        }
    }

    /// Copies the locally owned entries into `out` (as many as this rank owns).
    pub fn get_local(&self, out: &mut [f64]) -> Result<()> {
        let mut wrong = None;
        self.with_local(|a| match a.len() == out.len() {
            true => out.copy_from_slice(a),
            false => wrong = Some(a.len()),
        })?;
        match wrong {
            None => Ok(()),
            Some(n) => Err(error(format!("room for {} values, but this rank owns {n}", out.len()))),
        }
    }

    /// The locally owned entries, copied out.
    pub fn local(&self) -> Result<Vec<f64>> {
        let mut out = Vec::new();
        self.with_local(|a| out.extend_from_slice(a))?;
        Ok(out)
    }

    /// Reads the locally owned entries.
    pub fn with_local(&self, f: impl FnOnce(&[f64])) -> Result<()> {
        let (lo, hi) = self.ownership()?;
        let mut p: *const f64 = ptr::null();
        // SAFETY: the array has hi − lo entries until it is restored.
        check(unsafe { ffi::VecGetArrayRead(self.raw, &mut p) })?;
        f(unsafe { std::slice::from_raw_parts(p, hi - lo) });
        check(unsafe { ffi::VecRestoreArrayRead(self.raw, &mut p) })
    }

    /// Writes the locally owned entries.
    pub fn with_local_mut(&mut self, f: impl FnOnce(&mut [f64])) -> Result<()> {
        let (lo, hi) = self.ownership()?;
        let mut p: *mut f64 = ptr::null_mut();
        // SAFETY: as above, writable.
        check(unsafe { ffi::VecGetArray(self.raw, &mut p) })?;
        f(unsafe { std::slice::from_raw_parts_mut(p, hi - lo) });
        check(unsafe { ffi::VecRestoreArray(self.raw, &mut p) })
    }

    /// The global index range [lo, hi) this rank owns.
    pub fn ownership(&self) -> Result<(usize, usize)> {
        let (mut lo, mut hi) = (0, 0);
        check(unsafe { ffi::VecGetOwnershipRange(self.raw, &mut lo, &mut hi) })?;
        Ok((lo as usize, hi as usize))
    }

    /// ‖x‖_∞ (collective).
    pub fn norm_max(&self) -> Result<f64> {
        let mut v = 0.0;
        check(unsafe { ffi::VecNorm(self.raw, ffi::NormType::NORM_INFINITY, &mut v) })?;
        Ok(v)
    }

    /// self ← self + a x.
    pub fn axpy(&mut self, a: f64, x: &Vector) -> Result<()> {
        check(unsafe { ffi::VecAXPY(self.raw, a, x.raw) })
    }

    /// A vector of the same layout (entries unset).
    pub fn duplicate(&self) -> Result<Vector> {
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::VecDuplicate(self.raw, &mut raw) })?;
        Ok(Vector {
            raw,
            _session: self._session.clone(),
        })
    }
}

impl Drop for Vector {
    fn drop(&mut self) {
        unsafe { ffi::VecDestroy(&mut self.raw) };
    }
}

/// Gathers a distributed vector whole onto every rank (VecScatterCreateToAll).
pub struct AllGather {
    scatter: ffi::VecScatter,
    whole: Vector,
}

unsafe impl Send for AllGather {}

impl AllGather {
    pub fn new(like: &Vector) -> Result<Self> {
        let (mut scatter, mut whole) = (ptr::null_mut(), ptr::null_mut());
        check(unsafe { ffi::VecScatterCreateToAll(like.raw, &mut scatter, &mut whole) })?;
        Ok(AllGather {
            scatter,
            whole: Vector {
                raw: whole,
                _session: like._session.clone(),
            },
        })
    }

    /// All entries of `x` in global order (collective).
    pub fn gather(&mut self, x: &Vector, f: impl FnOnce(&[f64])) -> Result<()> {
        use ffi::{InsertMode::INSERT_VALUES, ScatterMode::SCATTER_FORWARD};
        check(unsafe { ffi::VecScatterBegin(self.scatter, x.raw, self.whole.raw, INSERT_VALUES, SCATTER_FORWARD) })?;
        check(unsafe { ffi::VecScatterEnd(self.scatter, x.raw, self.whole.raw, INSERT_VALUES, SCATTER_FORWARD) })?;
        self.whole.with_local(f)
    }
}

impl Drop for AllGather {
    fn drop(&mut self) {
        unsafe { ffi::VecScatterDestroy(&mut self.scatter) };
    }
}

/// Chosen entries of a distributed vector on the rank that wants them, and sums back to their
/// owners (VecScatterCreate with a sequential vector): the ghost values of a partition.
pub struct Scatter {
    scatter: ffi::VecScatter,
    local: Vector,
}

unsafe impl Send for Scatter {}

impl Scatter {
    /// A scatter of the global entries `indices` (in `like`'s layout, in the order wanted; any
    /// rank's) to this rank (collective).
    pub fn new(like: &Vector, indices: &[Int]) -> Result<Self> {
        let n = int(indices.len(), "scattered entries")?;
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::VecCreateSeq(comm_self(), n, &mut raw) })?;
        let local = Vector {
            raw,
            _session: like._session.clone(),
        };
        let mut from = ptr::null_mut();
        check(unsafe {
            ffi::ISCreateGeneral(
                comm_self(),
                n,
                indices.as_ptr(),
                ffi::PetscCopyMode::PETSC_COPY_VALUES,
                &mut from,
            )
        })?;
        let mut scatter = ptr::null_mut();
        // A null target index set: the whole local vector, in order.
        let created = check(unsafe { ffi::VecScatterCreate(like.raw, from, local.raw, ptr::null_mut(), &mut scatter) });
        unsafe { ffi::ISDestroy(&mut from) };
        created?;
        Ok(Scatter { scatter, local })
    }

    /// out[i] = x[indices[i]] (collective).
    pub fn gather(&mut self, x: &Vector, out: &mut [f64]) -> Result<()> {
        use ffi::{InsertMode::INSERT_VALUES, ScatterMode::SCATTER_FORWARD};
        check(unsafe { ffi::VecScatterBegin(self.scatter, x.raw, self.local.raw, INSERT_VALUES, SCATTER_FORWARD) })?;
        check(unsafe { ffi::VecScatterEnd(self.scatter, x.raw, self.local.raw, INSERT_VALUES, SCATTER_FORWARD) })?;
        self.local.get_local(out)
    }

    /// y[indices[i]] += values[i] on every rank, summed at the owners (collective).
    pub fn add_back(&mut self, values: &[f64], y: &mut Vector) -> Result<()> {
        use ffi::{InsertMode::ADD_VALUES, ScatterMode::SCATTER_REVERSE};
        self.local.set_local(values)?;
        check(unsafe { ffi::VecScatterBegin(self.scatter, self.local.raw, y.raw, ADD_VALUES, SCATTER_REVERSE) })?;
        check(unsafe { ffi::VecScatterEnd(self.scatter, self.local.raw, y.raw, ADD_VALUES, SCATTER_REVERSE) })
    }
}

impl Drop for Scatter {
    fn drop(&mut self) {
        unsafe { ffi::VecScatterDestroy(&mut self.scatter) };
    }
}

/// MUMPS's memory of a Cholesky factor, in MB (10⁶ bytes) as MUMPS reports it: estimated by its
/// analysis (INFO(15) on this rank, INFOG(16) the largest rank, INFOG(17) the sum) and, after the
/// numerical factorisation, allocated (INFO(16), INFOG(18), INFOG(19)); the factor's entries
/// (INFOG(3) estimated, INFOG(29) effective, summed over the ranks).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MumpsMemory {
    pub this_rank_mb: i64,
    pub largest_rank_mb: i64,
    pub total_mb: i64,
    pub factor_entries: i64,
}

/// MUMPS's INFO/INFOG integers of a factored matrix `f`; INFOG(3) and (29) are negative when
/// they count millions.
fn mumps_info(f: ffi::Mat, local: Int, largest: Int, total: Int, entries: Int) -> Result<MumpsMemory> {
    let (mut a, mut b, mut c, mut e) = (0, 0, 0, 0);
    check(unsafe { ffi::MatMumpsGetInfo(f, local, &mut a) })?;
    check(unsafe { ffi::MatMumpsGetInfog(f, largest, &mut b) })?;
    check(unsafe { ffi::MatMumpsGetInfog(f, total, &mut c) })?;
    check(unsafe { ffi::MatMumpsGetInfog(f, entries, &mut e) })?;
    let count = |v: Int| if v < 0 { -(v as i64) * 1_000_000 } else { v as i64 };
    Ok(MumpsMemory {
        this_rank_mb: a as i64,
        largest_rank_mb: b as i64,
        total_mb: c as i64,
        factor_entries: count(e),
    })
}

/// A distributed sparse matrix (MPIAIJ; SeqAIJ-compatible on one rank) with `block`-sized
/// node blocks, each rank owning a contiguous range of rows.
pub struct Matrix {
    raw: ffi::Mat,
    session: Arc<Session>,
}

unsafe impl Send for Matrix {}

impl Matrix {
    /// A square `global` × `global` MPIAIJ matrix whose `local_rows` rows this rank owns, with
    /// `diagonal_nnz[i]` entries of owned row i in the owned columns and `off_diagonal_nnz[i]`
    /// in the others (collective). Inserting outside that pattern is an error, not a
    /// reallocation.
    pub fn mpiaij(
        petsc: &Petsc,
        local_rows: usize,
        global: usize,
        block: usize,
        diagonal_nnz: &[Int],
        off_diagonal_nnz: &[Int],
    ) -> Result<Self> {
        if diagonal_nnz.len() != local_rows || off_diagonal_nnz.len() != local_rows {
            return Err(error("preallocation arrays must have one entry per owned row"));
        }
        let (n, ng, bs) = (
            int(local_rows, "local rows")?,
            int(global, "rows")?,
            int(block, "block size")?,
        );
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::MatCreate(comm(), &mut raw) })?;
        let m = Matrix {
            raw,
            session: petsc.session.clone(),
        };
        check(unsafe { ffi::MatSetSizes(m.raw, n, n, ng, ng) })?;
        check(unsafe { ffi::MatSetType(m.raw, ffi::MATAIJ.as_ptr().cast()) })?;
        check(unsafe { ffi::MatSetBlockSize(m.raw, bs) })?;
        check(unsafe { ffi::MatSeqAIJSetPreallocation(m.raw, 0, diagonal_nnz.as_ptr()) })?;
        check(unsafe {
            ffi::MatMPIAIJSetPreallocation(m.raw, 0, diagonal_nnz.as_ptr(), 0, off_diagonal_nnz.as_ptr())
        })?;
        check(unsafe { ffi::MatSetOption(m.raw, ffi::MatOption::MAT_NEW_NONZERO_ALLOCATION_ERR, 1) })?;
        Ok(m)
    }

    /// Adds a dense row-major block `values` (rows × cols) at global `rows`, `cols`. Entries for
    /// rows owned elsewhere are sent there at [`Matrix::assemble`].
    pub fn add(&mut self, rows: &[Int], cols: &[Int], values: &[f64]) -> Result<()> {
        if values.len() != rows.len() * cols.len() {
            return Err(error("block size does not match its row and column indices"));
        }
        check(unsafe {
            ffi::MatSetValues(
                self.raw,
                rows.len() as Int,
                rows.as_ptr(),
                cols.len() as Int,
                cols.as_ptr(),
                values.as_ptr(),
                ffi::InsertMode::ADD_VALUES,
            )
        })
    }

    /// Finishes assembly (collective) and marks the matrix symmetric positive definite.
    pub fn assemble_spd(&mut self) -> Result<()> {
        use ffi::MatAssemblyType::MAT_FINAL_ASSEMBLY;
        check(unsafe { ffi::MatAssemblyBegin(self.raw, MAT_FINAL_ASSEMBLY) })?;
        check(unsafe { ffi::MatAssemblyEnd(self.raw, MAT_FINAL_ASSEMBLY) })?;
        check(unsafe { ffi::MatSetOption(self.raw, ffi::MatOption::MAT_SYMMETRIC, 1) })?;
        check(unsafe { ffi::MatSetOption(self.raw, ffi::MatOption::MAT_SPD, 1) })
    }

    /// A vector with the matrix's row layout (entries zero).
    pub fn vector(&self) -> Result<Vector> {
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::MatCreateVecs(self.raw, &mut raw, ptr::null_mut()) })?;
        let mut v = Vector {
            raw,
            _session: self.session.clone(),
        };
        v.with_local_mut(|a| a.fill(0.0))?;
        Ok(v)
    }

    /// y = A x (collective).
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        check(unsafe { ffi::MatMult(self.raw, x.raw, y.raw) })
    }

    /// Bytes of this rank's part of the matrix: its allocated entries (MatGetInfo, MAT_LOCAL:
    /// an 8-byte value and a 4-byte column index each) and its row arrays (MatGetInfo's own
    /// `memory` is only counted when PETSc logs its mallocs).
    pub fn local_bytes(&self) -> Result<f64> {
        // SAFETY: MatInfo is plain data that MatGetInfo fills.
        let mut info: ffi::MatInfo = unsafe { std::mem::zeroed() };
        check(unsafe { ffi::MatGetInfo(self.raw, ffi::MatInfoType::MAT_LOCAL, &mut info) })?;
        let (mut lo, mut hi) = (0, 0);
        check(unsafe { ffi::MatGetOwnershipRange(self.raw, &mut lo, &mut hi) })?;
        Ok(info.memory.max(12.0 * info.nz_allocated + 32.0 * (hi - lo) as f64))
    }

    /// MUMPS's analysis (ordering and symbolic Cholesky factorisation) of this matrix, without the
    /// numerical factorisation: what the factor will need (collective).
    pub fn mumps_estimate(&self) -> Result<MumpsMemory> {
        let mut f = ptr::null_mut();
        check(unsafe {
            ffi::MatGetFactor(
                self.raw,
                ffi::MATSOLVERMUMPS.as_ptr().cast(),
                ffi::MatFactorType::MAT_FACTOR_CHOLESKY,
                &mut f,
            )
        })?;
        // SAFETY: MatFactorInfo is plain data that MatFactorInfoInitialize fills.
        let mut info: ffi::MatFactorInfo = unsafe { std::mem::zeroed() };
        let analysed = check(unsafe { ffi::MatFactorInfoInitialize(&mut info) })
            // MUMPS orders the matrix itself: no permutation is passed.
            .and_then(|()| check(unsafe { ffi::MatCholeskyFactorSymbolic(f, self.raw, ptr::null_mut(), &info) }))
            .and_then(|()| mumps_info(f, 15, 16, 17, 3));
        unsafe { ffi::MatDestroy(&mut f) };
        analysed
    }

    /// Sets the rigid-body modes of the coordinates `coords` (a vector with this row layout
    /// holding the node coordinates, block size = dimension) as the near null space GAMG uses.
    pub fn set_rigid_body_modes(&mut self, coords: &mut Vector, dim: usize) -> Result<()> {
        check(unsafe { ffi::VecSetBlockSize(coords.raw, int(dim, "dimension")?) })?;
        let mut space = ptr::null_mut();
        check(unsafe { ffi::MatNullSpaceCreateRigidBody(coords.raw, &mut space) })?;
        let r = check(unsafe { ffi::MatSetNearNullSpace(self.raw, space) });
        unsafe { ffi::MatNullSpaceDestroy(&mut space) };
        r
    }
}

impl Drop for Matrix {
    fn drop(&mut self) {
        unsafe { ffi::MatDestroy(&mut self.raw) };
    }
}

/// A distributed dense block of `columns` vectors (MATDENSE, column-major local rows), for
/// many right-hand sides at once.
pub struct DenseBlock {
    raw: ffi::Mat,
    local_rows: usize,
    columns: usize,
    _session: Arc<Session>,
}

unsafe impl Send for DenseBlock {}

impl DenseBlock {
    /// `columns` zero columns with the row layout of `a` (collective).
    pub fn like(a: &Matrix, columns: usize) -> Result<Self> {
        let (mut lo, mut hi) = (0, 0);
        check(unsafe { ffi::MatGetOwnershipRange(a.raw, &mut lo, &mut hi) })?;
        let (mut rows, mut _cols) = (0, 0);
        check(unsafe { ffi::MatGetSize(a.raw, &mut rows, &mut _cols) })?;
        let mut raw = ptr::null_mut();
        check(unsafe {
            ffi::MatCreateDense(
                comm(),
                hi - lo,
                ffi::PETSC_DECIDE,
                rows,
                int(columns, "right-hand sides")?,
                ptr::null_mut(),
                &mut raw,
            )
        })?;
        let mut b = DenseBlock {
            raw,
            local_rows: (hi - lo) as usize,
            columns,
            _session: a.session.clone(),
        };
        b.with_local_mut(|a, _| a.fill(0.0))?;
        Ok(b)
    }

    /// The local rows of all columns, column-major with leading dimension = local rows.
    pub fn with_local_mut(&mut self, f: impl FnOnce(&mut [f64], usize)) -> Result<()> {
        let mut lda = 0;
        check(unsafe { ffi::MatDenseGetLDA(self.raw, &mut lda) })?;
        let mut p: *mut f64 = ptr::null_mut();
        check(unsafe { ffi::MatDenseGetArray(self.raw, &mut p) })?;
        let len = if self.columns == 0 {
            0
        } else {
            lda as usize * (self.columns - 1) + self.local_rows
        };
        f(unsafe { std::slice::from_raw_parts_mut(p, len) }, lda as usize);
        check(unsafe { ffi::MatDenseRestoreArray(self.raw, &mut p) })
    }

    pub fn columns(&self) -> usize {
        self.columns
    }
}

impl Drop for DenseBlock {
    fn drop(&mut self) {
        unsafe { ffi::MatDestroy(&mut self.raw) };
    }
}

/// How [`Solver`] solves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// A direct Cholesky factorisation by MUMPS (KSPPREONLY + PCCHOLESKY).
    MumpsCholesky,
    /// Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid (GAMG),
    /// to the relative residual `rtol`.
    CgGamg { rtol: f64, max_iterations: usize },
}

/// A linear solver for one matrix (KSP): the factor or preconditioner is built once, at
/// [`Solver::new`], and reused by every solve.
pub struct Solver {
    raw: ffi::KSP,
    method: Method,
    _session: Arc<Session>,
}

unsafe impl Send for Solver {}

impl Solver {
    /// Sets up the solver for `a` (collective): factorises it (MUMPS) or builds the multigrid
    /// hierarchy (GAMG). Options with the prefix `prefix` (e.g. `-hvi_ksp_rtol`) are applied
    /// after hvi's own.
    pub fn new(a: &Matrix, method: Method, prefix: &str) -> Result<Self> {
        let mut raw = ptr::null_mut();
        check(unsafe { ffi::KSPCreate(comm(), &mut raw) })?;
        let s = Solver {
            raw,
            method,
            _session: a.session.clone(),
        };
        check(unsafe { ffi::KSPSetOperators(s.raw, a.raw, a.raw) })?;
        let mut pc = ptr::null_mut();
        check(unsafe { ffi::KSPGetPC(s.raw, &mut pc) })?;
        match method {
            Method::MumpsCholesky => {
                check(unsafe { ffi::KSPSetType(s.raw, ffi::KSPPREONLY.as_ptr().cast()) })?;
                check(unsafe { ffi::PCSetType(pc, ffi::PCCHOLESKY.as_ptr().cast()) })?;
                check(unsafe { ffi::PCFactorSetMatSolverType(pc, ffi::MATSOLVERMUMPS.as_ptr().cast()) })?;
            }
            Method::CgGamg { rtol, max_iterations } => {
                check(unsafe { ffi::KSPSetType(s.raw, ffi::KSPCG.as_ptr().cast()) })?;
                check(unsafe { ffi::PCSetType(pc, ffi::PCGAMG.as_ptr().cast()) })?;
                check(unsafe {
                    ffi::KSPSetTolerances(
                        s.raw,
                        rtol,
                        0.0,
                        ffi::PETSC_DEFAULT as f64,
                        int(max_iterations, "iterations")?,
                    )
                })?;
            }
        }
        let prefix = cstring(prefix)?;
        check(unsafe { ffi::KSPSetOptionsPrefix(s.raw, prefix.as_ptr()) })?;
        check(unsafe { ffi::KSPSetFromOptions(s.raw) })?;
        check(unsafe { ffi::KSPSetUp(s.raw) })?;
        s.check_pc()?;
        Ok(s)
    }

    fn check_pc(&self) -> Result<()> {
        let mut pc = ptr::null_mut();
        check(unsafe { ffi::KSPGetPC(self.raw, &mut pc) })?;
        let mut reason = 0;
        check(unsafe { ffi::PCGetFailedReason(pc, &mut reason) })?;
        if reason != ffi::PCFailedReason_PC_NOERROR {
            return Err(error(format!(
                "the {} preconditioner failed (PCFailedReason {reason}: {})",
                self.name(),
                match reason {
                    ffi::PCFailedReason_PC_FACTOR_STRUCT_ZEROPIVOT
                    | ffi::PCFailedReason_PC_FACTOR_NUMERIC_ZEROPIVOT => "a zero pivot: the matrix is singular",
                    ffi::PCFailedReason_PC_FACTOR_OUTMEMORY => "out of memory",
                    _ => "see the PETSc manual",
                }
            )));
        }
        Ok(())
    }

    pub fn method(&self) -> Method {
        self.method
    }

    /// The memory MUMPS allocated for the factor (after [`Solver::new`]; None for GAMG).
    pub fn mumps_memory(&self) -> Result<Option<MumpsMemory>> {
        if self.method != Method::MumpsCholesky {
            return Ok(None);
        }
        let mut pc = ptr::null_mut();
        check(unsafe { ffi::KSPGetPC(self.raw, &mut pc) })?;
        let mut f = ptr::null_mut();
        check(unsafe { ffi::PCFactorGetMatrix(pc, &mut f) })?;
        mumps_info(f, 16, 18, 19, 29).map(Some)
    }

    pub fn name(&self) -> &'static str {
        match self.method {
            Method::MumpsCholesky => "MUMPS Cholesky",
            Method::CgGamg { .. } => "CG + GAMG",
        }
    }

    /// x = A⁻¹ b (collective); the iterations taken (1 for MUMPS).
    pub fn solve(&self, b: &Vector, x: &mut Vector) -> Result<usize> {
        check(unsafe { ffi::KSPSolve(self.raw, b.raw, x.raw) })?;
        self.converged()
    }

    /// X = A⁻¹ B for a block of right-hand sides (KSPMatSolve, collective).
    pub fn solve_block(&self, b: &DenseBlock, x: &mut DenseBlock) -> Result<usize> {
        check(unsafe { ffi::KSPMatSolve(self.raw, b.raw, x.raw) })?;
        self.converged()
    }

    fn converged(&self) -> Result<usize> {
        let mut reason = 0;
        check(unsafe { ffi::KSPGetConvergedReason(self.raw, &mut reason) })?;
        let mut its = 0;
        check(unsafe { ffi::KSPGetIterationNumber(self.raw, &mut its) })?;
        if reason < 0 {
            self.check_pc()?;
            return Err(error(format!(
                "the {} solve did not converge (KSPConvergedReason {reason}{}) after {its} iterations",
                self.name(),
                match reason {
                    ffi::KSPConvergedReason_KSP_DIVERGED_ITS => ": iteration limit reached",
                    ffi::KSPConvergedReason_KSP_DIVERGED_INDEFINITE_PC
                    | ffi::KSPConvergedReason_KSP_DIVERGED_INDEFINITE_MAT =>
                        ": the matrix or preconditioner is indefinite (is the body held against rigid motions?)",
                    ffi::KSPConvergedReason_KSP_DIVERGED_PC_FAILED => ": the preconditioner failed",
                    ffi::KSPConvergedReason_KSP_DIVERGED_NANORINF => ": not-a-number or infinity",
                    _ => "",
                }
            )));
        }
        Ok(its.max(1) as usize)
    }
}

impl Drop for Solver {
    fn drop(&mut self) {
        unsafe { ffi::KSPDestroy(&mut self.raw) };
    }
}
