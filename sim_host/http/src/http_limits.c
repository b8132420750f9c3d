/* What one client may take of the server: at most PER_ADDRESS_CONNECTIONS connections from one
 * address (libmicrohttpd counts them), REQUEST_LIMIT_S to deliver a whole request, and a lower
 * CPU priority than the bus loop for every connection thread.
 *
 * libmicrohttpd's own timeout is an idle timeout: a client sending one octet every 2 s keeps a
 * connection, and its thread, for ever. So each connection has a deadline: REQUEST_LIMIT_S
 * after it opened, or after the end of its previous answer (keep-alive). Once its request is
 * complete (headers and body; the handler runs) it has none until that answer ends, so an
 * action that takes its time and an event stream are never cut. A reaper thread shuts down
 * the socket of a connection past its deadline; libmicrohttpd then closes it as one the client
 * closed. The table is only touched by connection threads and the reaper, never the loop. */
#include <microhttpd.h>
#include <netdb.h>
#include <pthread.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "http_internal.h"
#include "sim_hal/host_clock.h"

#define REAP_EVERY_MS 200u
#define NS_PER_S 1000000000u

struct http_limits {
    rig_ctl_t *ctl;
    pthread_mutex_t lock; /* the table and stop, among connection threads and the reaper */
    pthread_cond_t wake;
    bool stop;
    pthread_t reaper;
    http_conn_t conns[MAX_CONNECTIONS];
    struct MHD_OptionItem options[3];
};

static void peer_text(struct MHD_Connection *conn, char *out, size_t n)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    snprintf(out, n, "?");
    if (ci == NULL || ci->client_addr == NULL) {
        return;
    }
    const struct sockaddr *sa = ci->client_addr;
    char host[48] = "?";
    char port[8] = "?";
    (void)getnameinfo(sa, sa->sa_family == AF_INET6 ? sizeof(struct sockaddr_in6)
                                                    : sizeof(struct sockaddr_in),
                      host, sizeof host, port, sizeof port, NI_NUMERICHOST | NI_NUMERICSERV);
    snprintf(out, n, sa->sa_family == AF_INET6 ? "[%s]:%s" : "%s:%s", host, port);
}

/* Runs in the accepting thread before it creates the connection's thread, which inherits its
 * scheduling: so every thread serving a client runs below the bus loop, and a flood of requests
 * on few cores takes the CPU from them, not from it. A real-time policy (dfp-sim started with
 * chrt, for a short watchdog on a busy machine) is dropped first: nice values do not apply to
 * it. Not being allowed to change either is harmless. */
static void lower_priority(void)
{
    struct sched_param none = {0};
    (void)pthread_setschedparam(pthread_self(), SCHED_OTHER, &none);
    (void)setpriority(PRIO_PROCESS, (id_t)gettid(), REQUEST_NICE);
}

static void closed_text(const http_conn_t *c, const char *why, char *text, size_t n)
{
    snprintf(text, n, "connection from %s closed: %s", c->peer, why);
}

/* Under the lock: at most PENDING_CONNECTIONS - 1 connections wait for a request, so a new
 * one fits; the one waiting longest is closed (slow clients, from however many addresses,
 * only ever push out each other and idle keep-alive connections). */
static void make_room(http_limits_t *l)
{
    unsigned pending = 0;
    http_conn_t *oldest = NULL;
    for (unsigned i = 0; i < MAX_CONNECTIONS; i++) {
        http_conn_t *c = &l->conns[i];
        if (c->used && c->deadline_ns != 0u) {
            pending++;
            oldest = oldest != NULL && oldest->deadline_ns <= c->deadline_ns ? oldest : c;
        }
    }
    if (pending + 1u > PENDING_CONNECTIONS && oldest != NULL) {
        (void)shutdown(oldest->fd, SHUT_RDWR);
        oldest->deadline_ns = 0u;
        if (!oldest->answered) {
            char text[RIG_CTL_TEXT];
            closed_text(oldest, "no complete request yet, and a new connection needed its place",
                        text, sizeof text);
            rig_ctl_event(l->ctl, rig_ctl_time_us(l->ctl), RIG_LOG_WARN, "http", "limit", text);
        }
    }
}

static void on_connection(void *cls, struct MHD_Connection *conn, void **socket_context,
                          enum MHD_ConnectionNotificationCode code)
{
    http_limits_t *l = cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        lower_priority();
        const union MHD_ConnectionInfo *fi =
            MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
        pthread_mutex_lock(&l->lock);
        make_room(l);
        for (unsigned i = 0; i < MAX_CONNECTIONS && fi != NULL; i++) {
            http_conn_t *c = &l->conns[i];
            if (!c->used) {
                *c = (http_conn_t){.owner = l, .used = true, .fd = fi->connect_fd,
                                     .deadline_ns = host_clock_mono_ns() +
                                                    (uint64_t)REQUEST_LIMIT_S * NS_PER_S};
                peer_text(conn, c->peer, sizeof c->peer);
                *socket_context = c;
                break;
            }
        }
        pthread_mutex_unlock(&l->lock);
        return;
    }
    /* Closed: libmicrohttpd says so before it closes the socket, so the reaper never shuts
     * down a descriptor that was reused meanwhile. */
    http_conn_t *c = *socket_context;
    if (c != NULL) {
        pthread_mutex_lock(&l->lock);
        c->used = false;
        pthread_mutex_unlock(&l->lock);
        *socket_context = NULL;
    }
}

static void set_deadline(struct MHD_Connection *conn, uint64_t deadline_ns, bool answered)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    http_conn_t *c = ci != NULL ? ci->socket_context : NULL;
    if (c != NULL) {
        pthread_mutex_lock(&c->owner->lock);
        c->deadline_ns = deadline_ns;
        c->answered = c->answered || answered;
        pthread_mutex_unlock(&c->owner->lock);
    }
}

void http_limits_delivered(struct MHD_Connection *conn)
{
    set_deadline(conn, 0u, false);
}

void http_limits_request_end(struct MHD_Connection *conn)
{
    set_deadline(conn, host_clock_mono_ns() + (uint64_t)REQUEST_LIMIT_S * NS_PER_S, true);
}

/* Under the lock: shuts down every connection past its deadline, and says so in the log for
 * one that never had a request answered. One that had is a browser's keep-alive connection
 * gone idle, closed every 10 s in ordinary use of the panel: not worth a warning. */
static void reap(http_limits_t *l)
{
    uint64_t now = host_clock_mono_ns();
    for (unsigned i = 0; i < MAX_CONNECTIONS; i++) {
        http_conn_t *c = &l->conns[i];
        if (c->used && c->deadline_ns != 0u && now > c->deadline_ns) {
            (void)shutdown(c->fd, SHUT_RDWR);
            c->deadline_ns = 0u;
            if (c->answered) {
                continue;
            }
            char text[RIG_CTL_TEXT];
            char why[64];
            snprintf(why, sizeof why, "no complete request within %u s",
                     (unsigned)REQUEST_LIMIT_S);
            closed_text(c, why, text, sizeof text);
            rig_ctl_event(l->ctl, rig_ctl_time_us(l->ctl), RIG_LOG_WARN, "http", "limit", text);
        }
    }
}

static void *reaper_main(void *arg)
{
    http_limits_t *l = arg;
    lower_priority();
    pthread_mutex_lock(&l->lock);
    while (!l->stop) {
        reap(l);
        uint64_t at = host_clock_mono_ns() + (uint64_t)REAP_EVERY_MS * 1000000u;
        struct timespec ts = {(time_t)(at / NS_PER_S), (long)(at % NS_PER_S)};
        (void)pthread_cond_timedwait(&l->wake, &l->lock, &ts);
    }
    pthread_mutex_unlock(&l->lock);
    return NULL;
}

http_limits_t *http_limits_new(rig_ctl_t *ctl)
{
    http_limits_t *l = calloc(1, sizeof *l);
    if (l == NULL) {
        return NULL;
    }
    l->ctl = ctl;
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    bool ok = pthread_mutex_init(&l->lock, NULL) == 0;
    ok = ok && pthread_cond_init(&l->wake, &ca) == 0;
    pthread_condattr_destroy(&ca);
    if (!ok || pthread_create(&l->reaper, NULL, reaper_main, l) != 0) {
        free(l);
        return NULL;
    }
    l->options[0] = (struct MHD_OptionItem){MHD_OPTION_PER_IP_CONNECTION_LIMIT,
                                            PER_ADDRESS_CONNECTIONS, NULL};
    l->options[1] = (struct MHD_OptionItem){MHD_OPTION_NOTIFY_CONNECTION,
                                            (intptr_t)on_connection, l};
    l->options[2] = (struct MHD_OptionItem){MHD_OPTION_END, 0, NULL};
    return l;
}

struct MHD_OptionItem *http_limits_options(http_limits_t *l)
{
    return l->options;
}

void http_limits_free(http_limits_t *l)
{
    if (l == NULL) {
        return;
    }
    pthread_mutex_lock(&l->lock);
    l->stop = true;
    pthread_cond_signal(&l->wake);
    pthread_mutex_unlock(&l->lock);
    pthread_join(l->reaper, NULL);
    pthread_mutex_destroy(&l->lock);
    pthread_cond_destroy(&l->wake);
    free(l);
}
