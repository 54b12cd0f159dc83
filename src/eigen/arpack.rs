//! Minimal FFI to ARPACK-NG's C-callable symmetric drivers `dsaupd_c` / `dseupd_c`
//! (Debian `libarpack2-dev`, 32-bit integers), and the global lock that serialises them:
//! ARPACK keeps state in Fortran SAVE variables and is not re-entrant.

use std::os::raw::{c_char, c_double, c_int};
use std::sync::Mutex;

/// Serialises every ARPACK call in the process (tests run on parallel threads).
pub static ARPACK_LOCK: Mutex<()> = Mutex::new(());

/// Makes ARPACK's BLAS single-threaded when it is OpenBLAS, whoever calls the library: a
/// threaded BLAS sums in another order, and that roundoff moved the Craig-Bampton attachment
/// block's rank cut (a continuous Gram spectrum at 1e-10), so a ROM built in a test process
/// differed from the CLI's (2624 against 2629 reduced DOFs). `openblas_set_num_threads` is
/// looked up at run time (absent with the reference BLAS, whose calls are serial anyway).
/// Called once, before the first ARPACK solve.
pub fn single_threaded_blas() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // SAFETY: dlsym with RTLD_DEFAULT and a NUL-terminated name only reads; the symbol,
        // when present, is OpenBLAS's `void openblas_set_num_threads(int)`.
        unsafe {
            let sym = libc::dlsym(libc::RTLD_DEFAULT, c"openblas_set_num_threads".as_ptr());
            if !sym.is_null() {
                let set: extern "C" fn(c_int) = std::mem::transmute(sym);
                set(1);
            }
        }
    });
}

/// The last LAPACK/BLAS argument error reported through `xerbla_`: routine name and the
/// position of the illegal argument.
static LAPACK_ERROR: Mutex<Option<(String, i32)>> = Mutex::new(None);

/// LAPACK's error handler, replacing the library's: the reference `XERBLA` prints
/// `** On entry to ... had an illegal value` on stdout (mixing into a `--json` output) and the
/// run went on to exit 0 without a result. Here the routine and argument are recorded and the
/// caller ([`take_lapack_error`]) turns them into an error; LAPACK returns from the failing
/// routine as it does after printing. Fortran passes the name's length as a trailing hidden
/// argument (gfortran: `size_t`). The symbol is exported from the executable by build.rs
/// (`--export-dynamic-symbol`) so that the shared LAPACK resolves to it.
///
/// # Safety
/// Called by LAPACK with a pointer to at least `len` bytes of name and a pointer to an integer.
#[no_mangle]
pub unsafe extern "C" fn xerbla_(srname: *const c_char, info: *const c_int, len: usize) {
    let name = if srname.is_null() {
        String::from("?")
    } else {
        let bytes = std::slice::from_raw_parts(srname as *const u8, len.min(32));
        String::from_utf8_lossy(bytes).trim().to_string()
    };
    let arg = if info.is_null() { 0 } else { *info };
    let mut slot = LAPACK_ERROR.lock().unwrap_or_else(|p| p.into_inner());
    slot.get_or_insert((name, arg));
}

/// Takes the LAPACK argument error recorded since the last call, if any.
pub fn take_lapack_error() -> Option<(String, i32)> {
    LAPACK_ERROR
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .take()
}

extern "C" {
    pub fn dsaupd_c(
        ido: *mut c_int,
        bmat: *const c_char,
        n: c_int,
        which: *const c_char,
        nev: c_int,
        tol: c_double,
        resid: *mut c_double,
        ncv: c_int,
        v: *mut c_double,
        ldv: c_int,
        iparam: *mut c_int,
        ipntr: *mut c_int,
        workd: *mut c_double,
        workl: *mut c_double,
        lworkl: c_int,
        info: *mut c_int,
    );
    pub fn dseupd_c(
        rvec: c_int,
        howmny: *const c_char,
        select: *const c_int,
        d: *mut c_double,
        z: *mut c_double,
        ldz: c_int,
        sigma: c_double,
        bmat: *const c_char,
        n: c_int,
        which: *const c_char,
        nev: c_int,
        tol: c_double,
        resid: *mut c_double,
        ncv: c_int,
        v: *mut c_double,
        ldv: c_int,
        iparam: *mut c_int,
        ipntr: *mut c_int,
        workd: *mut c_double,
        workl: *mut c_double,
        lworkl: c_int,
        info: *mut c_int,
    );
}

/// Meaning of a dsaupd `info` code (ARPACK documentation of dsaupd).
pub fn saupd_message(info: i32) -> &'static str {
    match info {
        1 => "maximum number of Arnoldi update iterations reached",
        3 => "no shifts could be applied during an implicit restart: increase ncv",
        -1 => "n must be positive",
        -2 => "nev must be positive",
        -3 => "ncv must satisfy nev < ncv <= n",
        -4 => "the maximum number of iterations must be positive",
        -5 => "'which' is invalid",
        -6 => "bmat must be 'I' or 'G'",
        -7 => "length of private work array is not sufficient",
        -8 => "error return from the tridiagonal eigenvalue calculation",
        -9 => "starting vector is zero",
        -10 => "iparam(7) (mode) is invalid",
        -11 => "mode 1 is incompatible with bmat = 'G'",
        -12 => "iparam(1) must be 0 or 1",
        -13 => "nev and which = 'BE' are incompatible",
        -9999 => "could not build an Arnoldi factorisation",
        _ => "unknown ARPACK error",
    }
}

/// Meaning of a dseupd `info` code.
pub fn seupd_message(info: i32) -> &'static str {
    match info {
        -14 => "dsaupd did not find any eigenvalues to sufficient accuracy",
        -15 => "howmny must be 'A' or 'S' when rvec is true",
        -16 => "howmny = 'S' is not implemented",
        -17 => "dseupd got a different count of converged Ritz values than dsaupd",
        -8 => "error return from the tridiagonal eigenvalue calculation (LAPACK dsteqr)",
        _ => saupd_message(info),
    }
}
