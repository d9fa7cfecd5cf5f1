/*
 * canif C ABI, version 1: a CAN interface device (an EL6751-like process
 * image and CAN controller) in a shared library, driven in process by
 * `canif run --iut lib:path/to/libdevice.so`.
 *
 * The calls are those of the adapter protocol (docs/adapter-protocol.md),
 * version 1, as functions: canif calls them from one thread, one at a time.
 * Every multi-byte field of the images is little-endian, as the process image
 * is. A library exports every function below; canif checks
 * canif_abi_version() first and refuses a library of another version.
 *
 * To run the device under AddressSanitizer, build it with
 * -fsanitize=address and start canif with the sanitizer's runtime preloaded:
 *   LD_PRELOAD=$(cc -print-file-name=libasan.so) ASAN_OPTIONS=detect_leaks=0 \
 *       canif run --iut lib:./libdevice.so
 * (tests/c_abi.rs shows an overflow of the input image caught that way).
 */
#ifndef CANIF_H
#define CANIF_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CANIF_ABI_VERSION 1u

/* A CAN frame. `len` is the data length (for a remote frame the requested
 * length, with no data); `data` holds `len` bytes (at most 64, FD). Flags are
 * 0 or 1; `brs` and `esi` only with `fd`. */
typedef struct canif_frame {
    uint32_t id;
    uint8_t extended;
    uint8_t rtr;
    uint8_t fd;
    uint8_t brs;
    uint8_t esi;
    uint8_t len;
    uint8_t data[64];
} canif_frame;

/* One row of the filter table, in table order (first match decides). */
typedef struct canif_filter {
    uint8_t accept;   /* 1 accept, 0 reject */
    uint8_t is_range; /* 1: from..to; 0: code/mask */
    uint32_t from_or_code;
    uint32_t to_or_mask;
} canif_filter;

/* What the profile offers (configure.capabilities). */
typedef struct canif_capabilities {
    uint8_t base11, ext29, fd, fast_queue, optimized_queue;
    uint8_t transaction_number, transaction_number_only_ext29, time_stamp;
    uint8_t filters, info_data, distributed_clocks;
    uint8_t max_slots;
    uint32_t rx_queue_depth, tx_queue_depth;
} canif_capabilities;

/* The interface as the PLC configured it (configure.config). */
typedef struct canif_config {
    uint8_t format; /* 0: 11-bit, 1: 29-bit, 2: CAN FD */
    uint8_t queue;  /* 0: standard, 1: optimized, 2: fast */
    uint8_t transaction_number, time_stamp;
    uint8_t tx_slots, rx_slots;
    uint8_t distributed_clocks; /* 1: sync1_shift_ns applies */
    uint64_t sync1_shift_ns;
    uint32_t nominal_timing, data_timing;
    uint32_t output_size, input_size;
    uint32_t filter_count;
    const canif_filter *filters;
} canif_config;

/* The controller's status and counters (controller_status). */
typedef struct canif_status {
    uint8_t bus_off, error_passive, node_active, warning_limit, overload, bus_idle, core_running;
    uint32_t transceiver_delay, ack_errors, bit_errors, crc_errors, form_errors, stuff_errors;
    uint32_t receive_error_counter, transmit_error_counter;
} canif_status;

/* CANIF_ABI_VERSION of the header the library was built with. */
uint32_t canif_abi_version(void);

/* A device for this configuration, or NULL when the device refuses it (a
 * legitimate answer): then a reason, NUL-terminated, in `reason`. */
void *canif_create(const canif_config *config, const canif_capabilities *caps,
                   char *reason, size_t reason_size);

void canif_destroy(void *device);

/* One CAN interface cycle: the output image arrived at `now_ns`; write the new
 * input image (exactly input_size bytes). 0: done; anything else: the device
 * broke (an error, not a non-conformance). */
int canif_cycle(void *device, uint64_t now_ns, const uint8_t *outputs, size_t outputs_size,
                uint8_t *inputs, size_t inputs_size);

/* The controller received `frame`; its last bit ended at `end_ns`. */
void canif_receive(void *device, const canif_frame *frame, uint64_t end_ns);

/* The controller is idle at `now_ns`: 1 and the frame it starts in `frame`,
 * or 0. `next_ns`: when a held frame (Distributed Clocks) becomes due, or
 * UINT64_MAX. */
int canif_poll_transmit(void *device, uint64_t now_ns, canif_frame *frame, uint64_t *next_ns);

/* The frame it started is on the bus. */
void canif_transmit_complete(void *device);

void canif_controller_status(void *device, const canif_status *status);

#ifdef __cplusplus
}
#endif

#endif
