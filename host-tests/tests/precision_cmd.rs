//! The precision command prints the line for every format and distance, and the PNG it names exists.

use std::process::Command;

#[test]
fn precision_command_prints_every_format_at_every_distance() {
    let out = Command::new(env!("CARGO_BIN_EXE_precision"))
        .args(["--near", "10", "--far", "1000", "--at", "10,20,100,1000"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let plot = text
        .lines()
        .next()
        .unwrap()
        .strip_prefix("plot=")
        .expect("plot= first");
    assert!(std::path::Path::new(plot).exists(), "{plot}");
    let lines: Vec<&str> = text.lines().skip(1).collect();
    let names = [
        "W16",
        "W16F",
        "W24F",
        "W24F-scaled",
        "W32F",
        "Z16",
        "Z24",
        "Z32F",
        "RZ32F",
        "LZ16",
    ];
    assert_eq!(lines.len(), names.len() * 4);
    let mut k = 0;
    for name in names {
        for d in ["10", "20", "100", "1000"] {
            let keys: Vec<&str> = lines[k]
                .split(' ')
                .map(|kv| kv.split('=').next().unwrap())
                .collect();
            assert_eq!(
                keys,
                ["format", "near", "far", "d", "stored", "step"],
                "{}",
                lines[k]
            );
            assert!(
                lines[k].starts_with(&format!("format={name} near=10 far=1000 d={d} ")),
                "{}",
                lines[k]
            );
            k += 1;
        }
    }
    let value = |line: &str, key: &str| -> f64 {
        line.split(' ')
            .find_map(|kv| kv.strip_prefix(key))
            .unwrap()
            .parse()
            .unwrap()
    };
    // Seed 002 (near 10 / far 1000): Z is half way 10 units past the near plane and past 90% at 100 (Z16 rounds
    // Z to 1/65535, printed to 6 decimals).
    let z16 = |d: &str| {
        lines
            .iter()
            .find(|l| l.starts_with(&format!("format=Z16 near=10 far=1000 d={d} ")))
            .unwrap()
    };
    assert!((value(z16("20"), "stored=") - 50.0 / 99.0).abs() < 1e-5);
    assert!((value(z16("100"), "stored=") - 10.0 / 11.0).abs() < 1e-5);
    // W16's step is W_far / 65535 at every distance.
    for l in lines.iter().filter(|l| l.starts_with("format=W16 ")) {
        assert!(
            (value(l, "step=") / (1000.0 / 65535.0) - 1.0).abs() < 1e-5,
            "{l}"
        );
    }
}
