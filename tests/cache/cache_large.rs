//! `#CACHE LOAD` of a file larger than a tick's inline read budget: the loader thread reads
//! it, the line waits for it, and the cached subroutine then runs from memory.

use crate::support::Rig;
use ncchannel::INLINE_READ_BYTES_PER_TICK;

#[test]
fn a_large_file_is_cached_off_the_tick_and_runs_from_the_cache() {
    let lines = 3 * INLINE_READ_BYTES_PER_TICK as usize / 8;
    let mut sub = String::new();
    for i in 0..lines {
        sub.push_str(&format!("P1={i}\n"));
    }
    sub.push_str("X4\nM17\n");
    let rig = Rig::with_cache(Some((2, sub.len() as u32)), "");
    rig.program("big.cyc", &sub);
    rig.program(
        "main.nc",
        "N1 G01 X1 F6000\n#CACHE LOAD[FILE=big.cyc]\nL big.cyc\nL big.cyc\nN2 Y2\nM30\n",
    );
    let r = rig.run("main.nc", None, 1_000_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.error_codes());
    let ops: Vec<&str> = r
        .of("cache")
        .iter()
        .map(|e| e["op"].as_str().unwrap())
        .collect();
    assert_eq!(
        ops,
        ["load", "hit", "hit"],
        "loaded once, both calls from the cache"
    );
    let texts = r.block_texts();
    assert_eq!(
        texts.iter().filter(|t| t.starts_with("#CACHE")).count(),
        1,
        "the waiting line took effect once"
    );
    assert_eq!(texts.iter().filter(|t| *t == "M17").count(), 2);
    assert_eq!((r.position('X'), r.position('Y')), (4.0, 2.0));
    let files = r.machine.channels()[0].report().store;
    assert_eq!((files.opens, files.loaded_off_tick), (2, 1), "{files:?}");
    assert!(files.max_tick_read_bytes <= INLINE_READ_BYTES_PER_TICK);
}
