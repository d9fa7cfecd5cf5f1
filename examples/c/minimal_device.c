/*
 * A tiny CAN interface device in C, written only from include/canif.h and
 * docs/adapter-protocol.md: the plain buffered 11-bit interface with filters —
 * the Tx/Rx counter handshake, a send queue with back-pressure, a receive
 * queue with tail drop, the filter table (first match decides). It refuses
 * every other configuration.
 *
 *   cc -shared -fPIC -O2 -Iinclude -o libminimal.so examples/c/minimal_device.c
 *   cargo run --release -- run --iut lib:./libminimal.so --profile fc510x-before-fw2.14
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canif.h"

#define SLOT 10    /* 11-bit message: COB ID word + 8 bytes */
#define HEADER 6   /* TxCounter, RxCounter, NoOfMessages */
#define MAX_QUEUE 4096

typedef struct {
    uint16_t id;
    uint8_t rtr, len, data[8];
} message;

typedef struct {
    message items[MAX_QUEUE];
    size_t head, count, depth;
} queue;

typedef struct {
    uint8_t tx_slots, rx_slots;
    canif_filter filters[64];
    uint32_t filter_count;
    queue send, receive;
    int in_flight;
    size_t input_size;
    uint8_t inputs[];
} device;

static uint16_t u16(const uint8_t *b, size_t at) { return (uint16_t)(b[at] | (b[at + 1] << 8)); }

static void put16(uint8_t *b, size_t at, uint16_t v) {
    b[at] = (uint8_t)v;
    b[at + 1] = (uint8_t)(v >> 8);
}

static int push(queue *q, const message *m) {
    if (q->count >= q->depth || q->count >= MAX_QUEUE) return 0;
    q->items[(q->head + q->count) % MAX_QUEUE] = *m;
    q->count++;
    return 1;
}

static message pop(queue *q) {
    message m = q->items[q->head];
    q->head = (q->head + 1) % MAX_QUEUE;
    q->count--;
    return m;
}

uint32_t canif_abi_version(void) { return CANIF_ABI_VERSION; }

static const char *refusal(const canif_config *c, const canif_capabilities *caps) {
    if (c->format != 0) return "this example implements the 11-bit interface only";
    if (!caps->base11) return "the profile does not offer the 11-bit interface";
    if (c->queue != 0) return "this example implements the buffered queue only";
    if (c->transaction_number || c->time_stamp) return "no transaction number or time stamp here";
    if (c->distributed_clocks) return "no distributed clocks here";
    if (c->filter_count && !caps->filters) return "the profile offers no filters";
    if (c->filter_count > 64) return "at most 64 filter rows here";
    for (uint32_t i = 0; i < c->filter_count; i++) {
        const canif_filter *f = &c->filters[i];
        if (f->is_range && (f->from_or_code > f->to_or_mask || f->to_or_mask > 0x1FFFFFFF))
            return "malformed filter range";
        if (!f->is_range && (f->from_or_code | f->to_or_mask) > 0x1FFFFFFF)
            return "malformed filter mask";
    }
    if (c->tx_slots < 1 || c->tx_slots > caps->max_slots) return "slot count out of range";
    if (c->rx_slots < 1 || c->rx_slots > caps->max_slots) return "slot count out of range";
    return NULL;
}

void *canif_create(const canif_config *c, const canif_capabilities *caps, char *reason,
                   size_t reason_size) {
    const char *why = refusal(c, caps);
    if (why) {
        snprintf(reason, reason_size, "%s", why);
        return NULL;
    }
    device *d = calloc(1, sizeof(device) + c->input_size);
    if (!d) {
        snprintf(reason, reason_size, "out of memory");
        return NULL;
    }
    d->tx_slots = c->tx_slots;
    d->rx_slots = c->rx_slots;
    d->filter_count = c->filter_count;
    memcpy(d->filters, c->filters, c->filter_count * sizeof(canif_filter));
    d->send.depth = caps->tx_queue_depth;
    d->receive.depth = caps->rx_queue_depth;
    d->input_size = c->input_size;
    return d;
}

void canif_destroy(void *p) { free(p); }

int canif_cycle(void *p, uint64_t now_ns, const uint8_t *outputs, size_t outputs_size,
                uint8_t *inputs, size_t inputs_size) {
    device *d = p;
    (void)now_ns;
    if (inputs_size != d->input_size || outputs_size != HEADER + (size_t)SLOT * d->tx_slots)
        return 1;
    /* Tx: a changed TxCounter is a new batch; accept it when the queue has room. */
    uint16_t requested = u16(outputs, 0);
    if (requested != u16(d->inputs, 0)) {
        size_t count = u16(outputs, 4);
#ifndef CANIF_FAULT_TRUSTS_NO_OF_TX /* tests/c_abi.rs builds it without: reads past the outputs */
        if (count > d->tx_slots) count = d->tx_slots;
#endif
        /* the frame on the wire has left the queue (HS-TX-012) */
        size_t busy = d->send.count;
        if (busy == 0 || busy + count <= d->send.depth) {
            for (size_t i = 0; i < count; i++) {
                size_t at = HEADER + SLOT * i;
                uint16_t word = u16(outputs, at);
                message m = {.id = word >> 5, .rtr = (word & 0x10) != 0, .len = word & 0xF};
                if (m.len > 8) m.len = 8;
                if (!m.rtr) memcpy(m.data, outputs + at + 2, m.len);
                push(&d->send, &m);
            }
            put16(d->inputs, 0, requested);
        }
    }
    /* Rx: fill the image only when the PLC has released it. */
    if (u16(outputs, 2) == u16(d->inputs, 2) && d->receive.count) {
        size_t count = d->receive.count < d->rx_slots ? d->receive.count : d->rx_slots;
        for (size_t i = 0; i < d->rx_slots; i++) {
            size_t at = HEADER + SLOT * i;
            memset(d->inputs + at, 0, SLOT);
            if (i < count) {
                message m = pop(&d->receive);
                put16(d->inputs, at, (uint16_t)((m.id << 5) | (m.rtr ? 0x10 : 0) | m.len));
                if (!m.rtr) memcpy(d->inputs + at + 2, m.data, m.len);
            }
        }
        put16(d->inputs, 4, (uint16_t)count);
        put16(d->inputs, 2, (uint16_t)(u16(d->inputs, 2) + 1));
    }
    memcpy(inputs, d->inputs, d->input_size);
    return 0;
}

static int passes_filters(const device *d, uint32_t id) {
    int any_accept = 0;
    for (uint32_t i = 0; i < d->filter_count; i++) {
        const canif_filter *f = &d->filters[i];
        int hit = f->is_range ? (f->from_or_code <= id && id <= f->to_or_mask)
                              : ((id & f->to_or_mask) == (f->from_or_code & f->to_or_mask));
        if (hit) return f->accept;
        any_accept |= f->accept;
    }
    return !any_accept;
}

void canif_receive(void *p, const canif_frame *frame, uint64_t end_ns) {
    device *d = p;
    (void)end_ns;
    if (frame->extended || frame->fd || !passes_filters(d, frame->id)) return;
    message m = {.id = (uint16_t)frame->id, .rtr = frame->rtr, .len = frame->len};
    if (!m.rtr) memcpy(m.data, frame->data, m.len > 8 ? 8 : m.len);
    push(&d->receive, &m); /* full: the new frame is lost (tail drop) */
}

int canif_poll_transmit(void *p, uint64_t now_ns, canif_frame *frame, uint64_t *next_ns) {
    device *d = p;
    (void)now_ns;
    *next_ns = UINT64_MAX;
    if (d->in_flight || !d->send.count) return 0;
    message m = pop(&d->send);
    d->in_flight = 1;
    memset(frame, 0, sizeof *frame);
    frame->id = m.id;
    frame->rtr = m.rtr;
    frame->len = m.len;
    if (!m.rtr) memcpy(frame->data, m.data, m.len);
    return 1;
}

/* The send queue as canif_poll_transmit would hand it out: nothing is held
 * (no Distributed Clocks), so each frame may start at once. */
int canif_transmit_plan(void *p, uint64_t now_ns, canif_planned *plan, size_t capacity) {
    const device *d = p;
    size_t n = 0;
    for (; n < d->send.count && n < capacity; n++) {
        const message *m = &d->send.items[(d->send.head + n) % MAX_QUEUE];
        memset(&plan[n], 0, sizeof plan[n]);
        plan[n].frame.id = m->id;
        plan[n].frame.rtr = m->rtr;
        plan[n].frame.len = m->len;
        if (!m->rtr) memcpy(plan[n].frame.data, m->data, m->len);
        plan[n].not_before_ns = now_ns;
    }
    return (int)n;
}

void canif_transmit_complete(void *p) { ((device *)p)->in_flight = 0; }

void canif_controller_status(void *p, const canif_status *status) {
    (void)p;
    (void)status;
}
