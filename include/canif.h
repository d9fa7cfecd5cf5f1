/*
 * canif C ABI, version 1: a CAN interface device (an EL6751-like process
 * image and CAN controller) in a shared library, driven by
 * `canif run --iut lib:path/to/libdevice.so`. canif loads the library into a
 * process of its own (`canif lib-host`), whose images end at a guard page:
 * an access past one is reported with its offset and judged, and a crash
 * ends that process, not the run (`--lib-in-process` loads it into canif).
 * The host speaks to canif on descriptors of its own: the library may print
 * to stdout and stderr freely, and what it prints is in the report as its
 * output. Whatever it starts (a thread, a child, a daemon) ends with the run.
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
 *       canif run --lib-in-process --iut lib:./libdevice.so
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

/* One frame of a transmit plan, and the earliest time it may start. */
typedef struct canif_planned {
    canif_frame frame;
    uint64_t not_before_ns;
} canif_planned;

/* Optional. The frames the controller would start from `now_ns` on, in order,
 * if the bus took each at once and nothing else happened (not the one on the
 * wire), each with the earliest time it may start; at most `capacity` of them
 * in `plan`. Returns how many it wrote. It changes nothing: canif_poll_transmit
 * still hands out each frame, and must hand out the one planned first. The
 * plan is the device's word: canif judges its frames as the ones the device
 * sends, and a controller that then hands out another is an error.
 * With it, `canif lib-host` answers a cycle's requests in one exchange instead
 * of one per frame (docs/adapter-protocol.md, "steps"). */
int canif_transmit_plan(void *device, uint64_t now_ns, canif_planned *plan, size_t capacity);

/* Optional. What the device declares where the documents leave a choice
 * (docs/choices.md): "name=value" lines separated by '\n', NUL-terminated,
 * valid while the device lives; NULL declares nothing. Asked once, after
 * canif_create made the device. */
const char *canif_declares(void *device);

/* ---- The client role: a PLC-side client in a shared library ------------
 * `canif run --side plc --iut lib:path/to/libclient.so` (docs/plc-side.md).
 * The harness plays the device, the EtherCAT master and the application; the
 * library is the code that, once per PLC task, reads the input image and
 * writes the output image. A client library exports canif_abi_version and the
 * three functions below (none of the device's). */

/* A message between the application and the client: in a request, the
 * transaction number the application wants written (0 where the interface
 * has none) and time_stamp_ns 0; delivered, what the Rx message said. */
typedef struct canif_message {
    canif_frame frame;
    uint16_t transaction_number;
    uint64_t time_stamp_ns;
} canif_message;

/* A PLC program for this interface (`filters` and the timing fields are
 * those of the device and may be ignored). Called at the start and after
 * each PLC restart; NULL: the program cannot run (an error). */
void *canif_client_start(const canif_config *config);

void canif_client_stop(void *client);

/* One PLC task.
 * inputs:  the input image as the master delivers it (inputs_size bytes);
 * outputs: the output buffer as the master hands it (outputs_size bytes; it
 *          may hold zeros or an older image): leave the output image in it.
 *          Both sit inside the master's process image: the bytes behind them
 *          belong to other devices and must not be touched.
 * requests: the application's messages since the last task; set refused[i]
 *          to 1 for each one the client cannot send (request_count bytes).
 * delivered: room for delivered_capacity messages; write those the task read
 *          and hands to the application, in order, and their number in
 *          *delivered_count.
 * 0: done; anything else: the client broke (an error, not a failure). */
int canif_client_task(void *client, const uint8_t *inputs, size_t inputs_size,
                      uint8_t *outputs, size_t outputs_size,
                      const canif_message *requests, size_t request_count, uint8_t *refused,
                      canif_message *delivered, size_t delivered_capacity,
                      size_t *delivered_count);

/* Optional. After each canif_client_task: the transaction numbers of the Tx
 * messages that task learned were sent, in the order sent, written into
 * numbers (room for capacity); returns how many. Inputs.TransactionNumber
 * names the last message on the bus, so every message handed over before it
 * was sent too; Inputs.TxCounter only says the device queued the batch.
 * Judged on CL-TN-002; a library without it is not judged there. */
size_t canif_client_sent(void *client, uint16_t *numbers, size_t capacity);

/* Optional. What the client declares it is (docs/plc-side.md): "name=value"
 * lines separated by '\n', NUL-terminated, valid while the library is loaded;
 * NULL declares nothing. Asked before any canif_client_start, so a client
 * can say which interfaces it serves before it is started on one:
 * formats, queues, transaction-numbers, time-stamps, slots (or tx-slots and
 * rx-slots apart), direction,
 * application, restart, tells-sent. */
const char *canif_client_declares(void);

/* ---- The message structures of the process images -----------------------
 * One per frame format and option (000/001 section 6, 8.3), as the images
 * hold them: packed, little-endian. Generated from the model by
 * `canif export --messages --format c`; a test holds this block to it. The
 * images themselves depend on the slot counts: `canif export --profile P
 * --format c` writes them for one interface. */
#ifdef __cplusplus
#define CANIF_STATIC_ASSERT static_assert
#else
#define CANIF_STATIC_ASSERT _Static_assert
#endif
#pragma pack(push, 1)
/* 000/001 §8.3 */
typedef uint8_t CANFDMESSAGE[64];

/* 11-bit message: 10 bytes */
typedef struct CAN11MESSAGE {
    uint16_t CobID; /* byte 0: 000 §6: bits 0-3 length, bit 4 RTR, bits 5-15 identifier */
    uint8_t Data[8]; /* byte 2: the data bytes */
} CAN11MESSAGE;

/* 11-bit with transaction number message: 12 bytes */
typedef struct CAN11TXMESSAGE {
    uint16_t TransactionNumber; /* byte 0: 000 §5.2: any number; the last one sent comes back in the inputs */
    uint16_t CobID; /* byte 2: 000 §6: bits 0-3 length, bit 4 RTR, bits 5-15 identifier */
    uint8_t Data[8]; /* byte 4: the data bytes */
} CAN11TXMESSAGE;

/* 29-bit message: 14 bytes */
typedef struct CAN29MESSAGE {
    uint16_t Length; /* byte 0: 000 §6: data length 0..8 */
    uint32_t CobID; /* byte 2: 000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit */
    uint8_t Data[8]; /* byte 6: the data bytes */
} CAN29MESSAGE;

/* 29-bit with transaction number message: 16 bytes */
typedef struct CAN29TXMESSAGE {
    uint16_t TransactionNumber; /* byte 0: 000 §5.2: any number; the last one sent comes back in the inputs */
    uint16_t Length; /* byte 2: 000 §6: data length 0..8 */
    uint32_t CobID; /* byte 4: 000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit */
    uint8_t Data[8]; /* byte 8: the data bytes */
} CAN29TXMESSAGE;

/* 29-bit with time stamp message: 22 bytes */
typedef struct CAN29TSRXMESSAGE {
    uint16_t Length; /* byte 0: 000 §6: data length 0..8 */
    uint32_t CobID; /* byte 2: 000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit */
    uint8_t Data[8]; /* byte 6: the data bytes */
    uint64_t TimeStamp; /* byte 14: 000 §5.3: reception time in ns */
} CAN29TSRXMESSAGE;

/* CAN FD Tx (CANFDTXQUEUE) message: 72 bytes */
typedef struct CANFDTXQUEUE {
    uint16_t transactionNumber; /* byte 0: 000 §5.2: any number; the last one sent comes back in the inputs */
    uint8_t dataLength; /* byte 2: 000 §8.3.1: data length in bytes, 0..64 */
    uint8_t flags; /* byte 3: bit 0 EDL, bit 1 BSR, bit 2 ESI */
#define CANFDTXQUEUE_EDL 0x01u /* 000 §8.3: FD frame */
#define CANFDTXQUEUE_BSR 0x02u /* 000 §8.3: bit rate switch (BRS) */
#define CANFDTXQUEUE_ESI 0x04u /* 000 §8.3: error state indicator */
    uint32_t cobId; /* byte 4: 000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit */
    CANFDMESSAGE txData; /* byte 8: the data bytes */
} CANFDTXQUEUE;

/* CAN FD Rx (CANFDTSRXQUEUE) message: 78 bytes */
typedef struct CANFDTSRXQUEUE {
    uint8_t dataLength; /* byte 0: 000 §8.3.1: data length in bytes, 0..64 */
    uint8_t flags; /* byte 1: bit 0 EDL, bit 1 BSR, bit 2 ESI */
#define CANFDTSRXQUEUE_EDL 0x01u /* 000 §8.3: FD frame */
#define CANFDTSRXQUEUE_BSR 0x02u /* 000 §8.3: bit rate switch (BRS) */
#define CANFDTSRXQUEUE_ESI 0x04u /* 000 §8.3: error state indicator */
    uint32_t cobId; /* byte 2: 000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit */
    CANFDMESSAGE rxData; /* byte 6: the data bytes */
    uint64_t timeStamp; /* byte 70: 000 §5.3: reception time in ns */
} CANFDTSRXQUEUE;
#pragma pack(pop)

CANIF_STATIC_ASSERT(offsetof(CAN11MESSAGE, CobID) == 0, "CAN11MESSAGE.CobID at byte 0");
CANIF_STATIC_ASSERT(offsetof(CAN11MESSAGE, Data) == 2, "CAN11MESSAGE.Data at byte 2");
CANIF_STATIC_ASSERT(sizeof(CAN11MESSAGE) == 10, "CAN11MESSAGE is 10 bytes");
CANIF_STATIC_ASSERT(offsetof(CAN11TXMESSAGE, TransactionNumber) == 0, "CAN11TXMESSAGE.TransactionNumber at byte 0");
CANIF_STATIC_ASSERT(offsetof(CAN11TXMESSAGE, CobID) == 2, "CAN11TXMESSAGE.CobID at byte 2");
CANIF_STATIC_ASSERT(offsetof(CAN11TXMESSAGE, Data) == 4, "CAN11TXMESSAGE.Data at byte 4");
CANIF_STATIC_ASSERT(sizeof(CAN11TXMESSAGE) == 12, "CAN11TXMESSAGE is 12 bytes");
CANIF_STATIC_ASSERT(offsetof(CAN29MESSAGE, Length) == 0, "CAN29MESSAGE.Length at byte 0");
CANIF_STATIC_ASSERT(offsetof(CAN29MESSAGE, CobID) == 2, "CAN29MESSAGE.CobID at byte 2");
CANIF_STATIC_ASSERT(offsetof(CAN29MESSAGE, Data) == 6, "CAN29MESSAGE.Data at byte 6");
CANIF_STATIC_ASSERT(sizeof(CAN29MESSAGE) == 14, "CAN29MESSAGE is 14 bytes");
CANIF_STATIC_ASSERT(offsetof(CAN29TXMESSAGE, TransactionNumber) == 0, "CAN29TXMESSAGE.TransactionNumber at byte 0");
CANIF_STATIC_ASSERT(offsetof(CAN29TXMESSAGE, Length) == 2, "CAN29TXMESSAGE.Length at byte 2");
CANIF_STATIC_ASSERT(offsetof(CAN29TXMESSAGE, CobID) == 4, "CAN29TXMESSAGE.CobID at byte 4");
CANIF_STATIC_ASSERT(offsetof(CAN29TXMESSAGE, Data) == 8, "CAN29TXMESSAGE.Data at byte 8");
CANIF_STATIC_ASSERT(sizeof(CAN29TXMESSAGE) == 16, "CAN29TXMESSAGE is 16 bytes");
CANIF_STATIC_ASSERT(offsetof(CAN29TSRXMESSAGE, Length) == 0, "CAN29TSRXMESSAGE.Length at byte 0");
CANIF_STATIC_ASSERT(offsetof(CAN29TSRXMESSAGE, CobID) == 2, "CAN29TSRXMESSAGE.CobID at byte 2");
CANIF_STATIC_ASSERT(offsetof(CAN29TSRXMESSAGE, Data) == 6, "CAN29TSRXMESSAGE.Data at byte 6");
CANIF_STATIC_ASSERT(offsetof(CAN29TSRXMESSAGE, TimeStamp) == 14, "CAN29TSRXMESSAGE.TimeStamp at byte 14");
CANIF_STATIC_ASSERT(sizeof(CAN29TSRXMESSAGE) == 22, "CAN29TSRXMESSAGE is 22 bytes");
CANIF_STATIC_ASSERT(offsetof(CANFDTXQUEUE, transactionNumber) == 0, "CANFDTXQUEUE.transactionNumber at byte 0");
CANIF_STATIC_ASSERT(offsetof(CANFDTXQUEUE, dataLength) == 2, "CANFDTXQUEUE.dataLength at byte 2");
CANIF_STATIC_ASSERT(offsetof(CANFDTXQUEUE, flags) == 3, "CANFDTXQUEUE.flags at byte 3");
CANIF_STATIC_ASSERT(offsetof(CANFDTXQUEUE, cobId) == 4, "CANFDTXQUEUE.cobId at byte 4");
CANIF_STATIC_ASSERT(offsetof(CANFDTXQUEUE, txData) == 8, "CANFDTXQUEUE.txData at byte 8");
CANIF_STATIC_ASSERT(sizeof(CANFDTXQUEUE) == 72, "CANFDTXQUEUE is 72 bytes");
CANIF_STATIC_ASSERT(offsetof(CANFDTSRXQUEUE, dataLength) == 0, "CANFDTSRXQUEUE.dataLength at byte 0");
CANIF_STATIC_ASSERT(offsetof(CANFDTSRXQUEUE, flags) == 1, "CANFDTSRXQUEUE.flags at byte 1");
CANIF_STATIC_ASSERT(offsetof(CANFDTSRXQUEUE, cobId) == 2, "CANFDTSRXQUEUE.cobId at byte 2");
CANIF_STATIC_ASSERT(offsetof(CANFDTSRXQUEUE, rxData) == 6, "CANFDTSRXQUEUE.rxData at byte 6");
CANIF_STATIC_ASSERT(offsetof(CANFDTSRXQUEUE, timeStamp) == 70, "CANFDTSRXQUEUE.timeStamp at byte 70");
CANIF_STATIC_ASSERT(sizeof(CANFDTSRXQUEUE) == 78, "CANFDTSRXQUEUE is 78 bytes");

#ifdef __cplusplus
}
#endif

#endif
