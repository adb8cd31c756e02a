//! Link-time proof that `lbdem-kernels` is `no_std`: this staticlib brings its own panic handler, so it fails to
//! link if anything in the kernels pulls in `std` (which would bring a second `panic_impl`).
#![no_std]

use core::panic::PanicInfo;

#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    loop {}
}

/// Exercise the fluid kernels in both precisions so they are monomorphised and linked.
#[no_mangle]
pub extern "C" fn lbdem_nostd_probe(rho: f64) -> f64 {
    let f64eq = lbdem_kernels::fluid::d2q9::equilibrium(rho, [0.01, 0.0]);
    let f32eq = lbdem_kernels::fluid::d2q9::equilibrium(rho as f32, [0.01, 0.0]);
    f64eq[1] + f32eq[1] as f64
}
