/*
 * A PLC-side client of the CAN interface in C, through canif's C ABI (the
 * client role of include/canif.h), written from docs/adapter-protocol.md's
 * "Image offsets" and the 001 sample code:
 *
 *   cc -shared -fPIC -O2 -Iinclude -o libminimal_client.so examples/c/minimal_client.c
 *   cargo run --release -- run plc --iut lib:./libminimal_client.so
 *
 * Once per task it reads NoOfRxMessages messages (never more than the slots)
 * when Inputs.RxCounter differs from the Outputs.RxCounter it wrote, and
 * acknowledges by copying Inputs.RxCounter; it hands queued messages over
 * only while Outputs.TxCounter equals Inputs.TxCounter, then writes
 * Inputs.TxCounter + 1. It keeps its own output image and copies all of it
 * into the buffer the master hands it. With transaction numbers it tells
 * which messages were sent (canif_client_sent): every message up to the one
 * Inputs.TransactionNumber names.
 */
#include <stdlib.h>
#include <string.h>

#include "canif.h"

#define QUEUE 4096

typedef struct client {
    canif_config config;
    size_t tx_size, rx_size, rx_start;
    uint8_t *image; /* the output image, as this program keeps it */
    canif_message queue[QUEUE];
    size_t head, count;
    /* Transaction numbers handed over and not yet known to be sent, and
     * those this task learned were. */
    uint16_t in_flight[QUEUE];
    size_t in_flight_count;
    uint16_t sent[QUEUE];
    size_t sent_count;
} client;

static const uint8_t FD_SIZES[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

static uint32_t get(const uint8_t *b, size_t n) {
    uint32_t v = 0;
    for (size_t i = 0; i < n; i++) v |= (uint32_t)b[i] << (8 * i);
    return v;
}

static void put(uint8_t *b, uint32_t v, size_t n) {
    for (size_t i = 0; i < n; i++) b[i] = (uint8_t)(v >> (8 * i));
}

uint32_t canif_abi_version(void) { return CANIF_ABI_VERSION; }

void *canif_client_start(const canif_config *config) {
#ifdef CANIF_29BIT_NO_TN /* tests/c_abi_client.rs: a client of one interface, declaring it */
    if (config->format != 1 || config->transaction_number || config->time_stamp) return NULL;
#endif
    client *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->config = *config;
    c->config.filters = NULL;
    c->config.filter_count = 0;
    int tn = config->transaction_number, fd = config->format == 2;
    c->rx_start = (tn || fd) ? 8 : 6;
    if (config->format == 0) {
        c->tx_size = tn ? 12 : 10;
        c->rx_size = 10;
    } else if (config->format == 1) {
        c->tx_size = tn ? 16 : 14;
        c->rx_size = config->time_stamp ? 22 : 14;
    } else {
        c->tx_size = 72;
        c->rx_size = 78;
    }
    c->image = calloc(1, config->output_size);
    if (!c->image) {
        free(c);
        return NULL;
    }
    return c;
}

void canif_client_stop(void *handle) {
    client *c = handle;
    free(c->image);
    free(c);
}

static int fits(const client *c, const canif_frame *f) {
    if (c->config.format == 0) return !f->extended && !f->fd;
    if (c->config.format == 1) return !f->fd;
    return 1;
}

#ifdef CANIF_ZERO_NUMBERS /* tests/c_abi_client.rs: every transaction number 0 (000 §5.2 allows any) */
#define NUMBER(m) 0u
#else
#define NUMBER(m) (m)->transaction_number
#endif

static void encode(client *c, uint8_t *at, const canif_message *m) {
    const canif_frame *f = &m->frame;
    size_t len = f->rtr ? 0 : f->len;
    memset(at, 0, c->tx_size);
    if (c->config.format == 0) {
        if (c->config.transaction_number) {
            put(at, NUMBER(m), 2);
            at += 2;
        }
        put(at, (f->id << 5) | (f->rtr ? 0x10u : 0u) | f->len, 2);
        memcpy(at + 2, f->data, len);
        return;
    }
    uint32_t cob = f->id | (f->extended ? 0x80000000u : 0u) | (f->rtr ? 0x40000000u : 0u);
    if (c->config.format == 1) {
        if (c->config.transaction_number) {
            put(at, NUMBER(m), 2);
            at += 2;
        }
        put(at, f->len, 2);
        put(at + 2, cob, 4);
        memcpy(at + 6, f->data, len);
        return;
    }
    put(at, NUMBER(m), 2);
    at[2] = f->len;
    at[3] = (uint8_t)((f->fd ? 1 : 0) | (f->brs ? 2 : 0) | (f->esi ? 4 : 0));
    put(at + 4, cob, 4);
    memcpy(at + 8, f->data, len);
}

static canif_message decode(const client *c, const uint8_t *at) {
    canif_message m;
    memset(&m, 0, sizeof m);
    canif_frame *f = &m.frame;
    const uint8_t *data;
    size_t len;
    if (c->config.format == 0) {
        uint32_t word = get(at, 2);
        f->id = word >> 5;
        f->rtr = (word & 0x10) != 0;
        len = word & 0xF;
        if (len > 8) len = 8;
        data = at + 2;
    } else {
        uint32_t cob;
        if (c->config.format == 1) {
            len = get(at, 2);
            cob = get(at + 2, 4);
            data = at + 6;
            if (c->config.time_stamp) m.time_stamp_ns = get(at + 14, 4) | ((uint64_t)get(at + 18, 4) << 32);
        } else {
            len = at[0];
            f->fd = at[1] & 1;
            f->brs = f->fd && (at[1] & 2);
            f->esi = f->fd && (at[1] & 4);
            cob = get(at + 2, 4);
            data = at + 6;
            m.time_stamp_ns = get(at + 70, 4) | ((uint64_t)get(at + 74, 4) << 32);
        }
        f->id = cob & 0x1FFFFFFFu;
        f->extended = (cob & 0x80000000u) != 0;
        f->rtr = (cob & 0x40000000u) != 0;
        if (len > (f->fd ? 64u : 8u)) len = f->fd ? 64 : 8;
        if (f->fd) {
            size_t i = 0;
            while (FD_SIZES[i] < len) i++;
            len = FD_SIZES[i];
        }
    }
    f->len = (uint8_t)len;
    if (!f->rtr) memcpy(f->data, data, len);
    return m;
}

int canif_client_task(void *handle, const uint8_t *inputs, size_t inputs_size, uint8_t *outputs,
                      size_t outputs_size, const canif_message *requests, size_t request_count,
                      uint8_t *refused, canif_message *delivered, size_t delivered_capacity,
                      size_t *delivered_count) {
    client *c = handle;
    if (inputs_size != c->config.input_size || outputs_size != c->config.output_size) return 1;
    for (size_t i = 0; i < request_count; i++) {
        if (!fits(c, &requests[i].frame) || c->count == QUEUE) {
            refused[i] = 1;
            continue;
        }
        c->queue[(c->head + c->count++) % QUEUE] = requests[i];
    }
    *delivered_count = 0;
    /* Sent: up to the message Inputs.TransactionNumber names. */
    c->sent_count = 0;
    if (c->rx_start == 8) {
        uint16_t last = (uint16_t)get(inputs + 6, 2);
        for (size_t i = 0; i < c->in_flight_count; i++) {
            if (c->in_flight[i] != last) continue;
            c->sent_count = i + 1;
            memcpy(c->sent, c->in_flight, c->sent_count * sizeof c->sent[0]);
            c->in_flight_count -= c->sent_count;
            memmove(c->in_flight, c->in_flight + c->sent_count,
                    c->in_flight_count * sizeof c->in_flight[0]);
            break;
        }
    }
    /* Read: a new Inputs.RxCounter means NoOfRxMessages new messages. */
#ifdef CANIF_TX_ONLY /* tests/c_abi_client.rs: a client that only sends, declaring it or not */
    if (0) {
#else
    if (get(inputs + 2, 2) != get(c->image + 2, 2)) {
#endif
        size_t n = get(inputs + 4, 2);
#ifdef CANIF_FAULT_TRUSTS_COUNT /* tests/c_abi_client.rs: checks every slot NoOfRxMessages names, past the image */
        volatile uint8_t seen = 0;
        for (size_t i = 0; i < n; i++) seen ^= inputs[c->rx_start + i * c->rx_size];
        (void)seen;
#endif
#ifndef CANIF_FAULT_NO_BOUND /* the fault tests/c_abi_client.rs builds: no bound on NoOfRxMessages */
        if (n > c->config.rx_slots) n = c->config.rx_slots;
#endif
#ifdef CANIF_FAULT_SKIPS_LAST_RX /* tests/c_abi_client.rs: the last message of each batch is lost */
        if (n > 0) n--;
#endif
        if (n > delivered_capacity) n = delivered_capacity;
        for (size_t i = 0; i < n; i++) delivered[i] = decode(c, inputs + c->rx_start + i * c->rx_size);
        *delivered_count = n;
        memcpy(c->image + 2, inputs + 2, 2);
    }
    /* Send: only while the last batch is acknowledged. */
#ifdef CANIF_EMPTY_BATCHES /* tests/c_abi_client.rs: 000's sample without its > 0 guard (allowed, HS-TX-009) */
    if (get(c->image, 2) == get(inputs, 2)) {
#else
    if (get(c->image, 2) == get(inputs, 2) && c->count > 0) {
#endif
        size_t n = c->count < c->config.tx_slots ? c->count : c->config.tx_slots;
        for (size_t i = 0; i < n; i++) {
            encode(c, c->image + 6 + i * c->tx_size, &c->queue[c->head]);
            if (c->rx_start == 8 && c->in_flight_count < QUEUE)
                c->in_flight[c->in_flight_count++] = c->queue[c->head].transaction_number;
            c->head = (c->head + 1) % QUEUE;
            c->count--;
        }
        put(c->image + 4, (uint32_t)n, 2);
        put(c->image, (get(inputs, 2) + 1) & 0xFFFF, 2);
    }
    memcpy(outputs, c->image, outputs_size);
    return 0;
}

#ifndef CANIF_UNDECLARED /* tests/c_abi_client.rs builds it without: optional */
/* What this client is (docs/plc-side.md): it serves every interface the
 * profile offers at any slot count, both ways, as one stream; a restarted
 * program delivers the batch it finds in the image, which the program before
 * may have delivered already (P3). */
const char *canif_client_declares(void) {
#ifdef CANIF_TX_ONLY
    return "direction=tx\nslots=1..32\napplication=one-stream\nrestart=delivers-twice\n";
#elif defined(CANIF_29BIT_NO_TN)
    return "formats=29-bit\ntransaction-numbers=no\ntime-stamps=no\nslots=1..32\n"
           "application=one-stream\nrestart=delivers-twice\n";
#else
    return "direction=both\nslots=1..32\napplication=one-stream\nrestart=delivers-twice\n";
#endif
}
#endif

#ifndef CANIF_WITHOUT_SENT /* tests/c_abi_client.rs builds it without: optional */
size_t canif_client_sent(void *handle, uint16_t *numbers, size_t capacity) {
    client *c = handle;
    size_t n = c->sent_count < capacity ? c->sent_count : capacity;
    memcpy(numbers, c->sent, n * sizeof numbers[0]);
    return n;
}
#endif
