//! wraster on a Raspberry Pi Pico (RP2040, Cortex-M0+, thumbv6m-none-eabi) driving a 240x240 ST7789 over SPI.
//!
//! Renders the terrain demo (W_near 10, W_far 10000) once, then W4's torus rotating, frame after frame, through the
//! mesh path (each frame transformed once into 6 KiB, then drawn band by band), 16 rows at a time (a 320x16 colour
//! band and a 320x16 W16 band, 20 KiB, in RAM), and pushes the middle 240 columns of each finished band to the
//! display with `mipidsi`, so the whole 320x240 frame never exists in RAM. This board only builds here (there is no emulator for
//! it); the README says how to flash it.
//!
//! Wiring (SPI0): SCK GP18, MOSI GP19, CS GP17, DC GP16, RST GP20, backlight GP21 (high = on).
#![no_std]
#![no_main]

use embedded_graphics_core::pixelcolor::raw::RawU16;
use embedded_graphics_core::pixelcolor::Rgb565;
use embedded_hal::digital::OutputPin;
use mipidsi::interface::SpiInterface;
use mipidsi::models::ST7789;
use mipidsi::options::ColorInversion;
use panic_halt as _;
use rp2040_hal::clocks::{init_clocks_and_plls, Clock};
use rp2040_hal::fugit::RateExtU32;
use rp2040_hal::gpio::{FunctionSpi, Pins};
use rp2040_hal::{entry, pac, Sio, Spi, Timer, Watchdog};
use wraster::mesh::Projected;
use wraster::recip::Fast;
use wraster::scenes::torus::{TRIANGLES, VERTICES};
use wraster_board::{run_scene_cached, run_torus_with, NoCounter, SCENES, WIDTH};

/// The second-stage boot loader for the Pico's W25Q080 flash.
#[link_section = ".boot2"]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

const XTAL_HZ: u32 = 12_000_000;
const BAND_ROWS: usize = 16;
const SIDE: u16 = 240;
/// The display shows columns [LEFT, LEFT + 240) of the 320-wide frame.
const LEFT: usize = (WIDTH - SIDE) as usize / 2;

#[entry]
fn main() -> ! {
    let mut pac = pac::Peripherals::take().unwrap();
    let mut watchdog = Watchdog::new(pac.WATCHDOG);
    let clocks = init_clocks_and_plls(
        XTAL_HZ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    )
    .ok()
    .unwrap();
    let sio = Sio::new(pac.SIO);
    let pins = Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );
    let mut timer = Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);

    let sck = pins.gpio18.into_function::<FunctionSpi>();
    let mosi = pins.gpio19.into_function::<FunctionSpi>();
    let spi = Spi::<_, _, _, 8>::new(pac.SPI0, (mosi, sck)).init(
        &mut pac.RESETS,
        clocks.peripheral_clock.freq(),
        62_500_000u32.Hz(),
        embedded_hal::spi::MODE_3,
    );
    let cs = pins.gpio17.into_push_pull_output();
    let dc = pins.gpio16.into_push_pull_output();
    let rst = pins.gpio20.into_push_pull_output();
    let mut backlight = pins.gpio21.into_push_pull_output();
    let device = embedded_hal_bus::spi::ExclusiveDevice::new(spi, cs, timer).unwrap();
    let mut spi_buffer = [0u8; 512];
    let interface = SpiInterface::new(device, dc, &mut spi_buffer);
    let mut display = mipidsi::Builder::new(ST7789, interface)
        .display_size(SIDE, SIDE)
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(&mut timer)
        .unwrap();
    backlight.set_high().unwrap();

    let terrain = SCENES.iter().find(|s| s.name == "terrain").unwrap();
    let mut color = [0u16; WIDTH as usize * BAND_ROWS];
    let mut depth = [0u16; WIDTH as usize * BAND_ROWS];
    let mut push = |y0: u16, band: &[u16]| {
        let rows = band.len() / WIDTH as usize;
        let pixels = (0..rows).flat_map(|r| {
            band[r * WIDTH as usize + LEFT..r * WIDTH as usize + LEFT + SIDE as usize]
                .iter()
                .map(|&p| Rgb565::from(RawU16::new(p)))
        });
        let _ = display.set_pixels(0, y0, SIDE - 1, y0 + rows as u16 - 1, pixels);
    };
    // The terrain in bands with the standard scenes' plane cache: a triangle reaching several bands is set up once.
    let mut scene_cache = wraster_board::SceneCache::new();
    let _ = run_scene_cached::<Fast, _>(
        terrain,
        &mut color,
        &mut depth,
        &mut [],
        &mut scene_cache,
        &mut NoCounter,
        &mut push,
    );
    let mut verts = [Projected::default(); VERTICES];
    // Row bins for the 15 bands (`Rasterizer::bin_mesh`): each band sets up only the triangles that can reach it.
    let mut bins = [0u8; TRIANGLES];
    // The plane cache: a triangle reaching several bands has its depth-grid values computed once a frame.
    let mut cache = wraster_board::TorusCache::new();
    let mut k = 0;
    loop {
        let _ = run_torus_with::<Fast, _>(
            &mut color,
            &mut depth,
            &mut verts,
            &mut bins,
            &mut cache,
            &mut NoCounter,
            k..k + 1,
            &mut push,
        );
        // sin_cos is accurate for angles up to 6000 rad: 0.6 k stays within that
        k = (k + 1) % 10_000;
    }
}
