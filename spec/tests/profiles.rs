//! The profiles against the feature matrix of 000/001 §2, transcribed here a
//! second time by hand so that a slip in either copy shows.

use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::device::Device;
use canif_spec::Catalogue;

/// name, base11, ext29, fd, fast, optimized, transaction number, time stamp, InfoData, Rx queue.
type Row = (
    &'static str,
    bool,
    bool,
    bool,
    bool,
    bool,
    bool,
    bool,
    bool,
    usize,
);

#[rustfmt::skip]
const MATRIX: [Row; 9] = [
    //                        base11 ext29  fd     fast   optim. TN     TS     Info   Rx queue
    ("el6751-legacy",         true,  true,  false, false, true,  true,  false, false, 150),
    ("el6751-mdp",            true,  true,  false, true,  true,  true,  false, false, 150),
    ("ccat-before-fw1.17",    false, true,  false, false, false, false, false, false, 512),
    ("ccat",                  false, true,  false, false, false, true,  true,  false, 512),
    ("cx1500-m510",           true,  true,  false, false, false, false, false, false, 150),
    ("fc510x-before-fw2.14",  true,  false, false, false, false, false, false, false, 150),
    ("fc510x",                true,  true,  false, false, false, false, false, false, 150),
    ("fc532x",                true,  true,  true,  false, false, true,  true,  true,  512),
    ("cx-m530",               true,  true,  true,  false, false, true,  true,  true,  512),
];

/// Covers: PROF-001, PROF-006, PROF-007, PROF-008, PROF-009, PROF-012, RXQ-001, RXQ-002
#[test]
fn profiles_match_the_feature_matrix() {
    let catalogue = Catalogue::embedded().unwrap();
    for (name, base11, ext29, fd, fast, optimized, tn, ts, info, rx_depth) in MATRIX {
        let profile = catalogue
            .profile(name)
            .unwrap_or_else(|| panic!("profile {name}"));
        let caps = profile.model_capabilities();
        assert_eq!(
            (
                caps.base11,
                caps.ext29,
                caps.fd,
                caps.fast_queue,
                caps.optimized_queue,
                caps.transaction_number,
                caps.time_stamp,
                caps.info_data
            ),
            (base11, ext29, fd, fast, optimized, tn, ts, info),
            "{name}"
        );
        assert_eq!(caps.rx_queue_depth, rx_depth, "{name}");
        assert_eq!(caps.max_slots, 32, "{name}");
    }
    assert_eq!(catalogue.profiles.len(), MATRIX.len());
}

/// Covers: PROF-002, PROF-003, PROF-004, PROF-005, PROF-006, PROF-007, PROF-011, TN-004, TS-002
#[test]
fn each_profile_refuses_what_it_does_not_offer() {
    let catalogue = Catalogue::embedded().unwrap();
    for profile in &catalogue.profiles {
        let caps = profile.model_capabilities();
        for format in [
            FrameFormat::Base11,
            FrameFormat::Extended29,
            FrameFormat::Fd,
        ] {
            for queue in [QueueMode::Standard, QueueMode::Optimized, QueueMode::Fast] {
                for (tn, ts) in [(false, false), (true, false), (true, true)] {
                    let mut config = InterfaceConfig::new(format, 8);
                    config.queue = queue;
                    config.transaction_number = tn || format == FrameFormat::Fd;
                    config.time_stamp = ts || format == FrameFormat::Fd;
                    let offered = match format {
                        FrameFormat::Base11 => profile.has("base11"),
                        FrameFormat::Extended29 => profile.has("ext29"),
                        FrameFormat::Fd => profile.has("fd"),
                    } && match queue {
                        QueueMode::Standard => true,
                        QueueMode::Optimized => profile.has("optimized_queue"),
                        QueueMode::Fast => profile.has("fast_queue"),
                    };
                    let footnote1 = queue == QueueMode::Standard
                        || (format == FrameFormat::Base11 && !config.transaction_number);
                    let tn_ok = !config.transaction_number
                        || (profile.has("transaction_number")
                            && !(profile.transaction_number_only_ext29
                                && format == FrameFormat::Base11));
                    let footnote2 = !config.time_stamp
                        || (profile.has("timestamp")
                            && format != FrameFormat::Base11
                            && config.transaction_number);
                    let expected = offered && footnote1 && tn_ok && footnote2;
                    let verdict = Device::new(&caps, config.clone());
                    assert_eq!(
                        verdict.is_ok(),
                        expected,
                        "{}: {format:?} {queue:?} tn={} ts={}: {:?}",
                        profile.name,
                        config.transaction_number,
                        config.time_stamp,
                        verdict.err()
                    );
                }
            }
        }
        let mut too_many = InterfaceConfig::new(
            if profile.has("base11") {
                FrameFormat::Base11
            } else {
                FrameFormat::Extended29
            },
            33,
        );
        too_many.tx_slots = 8;
        assert!(
            Device::new(&caps, too_many).is_err(),
            "{}: 33 Rx slots",
            profile.name
        );
    }
}
