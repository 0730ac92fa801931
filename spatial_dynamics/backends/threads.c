/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * A batch on threads: run_batch releases the GIL and gives each of its POSIX threads (the
 * caller's included) a contiguous block of the batch's states, which the thread claims
 * chunk by chunk, each chunk run by run_states (kernels.c); a thread done with its block
 * claims the chunks left in the others'. Without POSIX threads and GCC/Clang atomics, the
 * caller runs them all.
 */
#include "_compiled.h"

#include <stdlib.h>
#ifndef _WIN32
#include <pthread.h>
#endif

/* Largest number of threads of one batch; each gets at least MIN_WORK body-states (states x
 * bodies, ~0.2 ms of work): starting a thread, and waiting for a core on a busy machine,
 * must cost less than what it takes over. */
#define MAX_THREADS 64
#define MIN_WORK 4096
/* The threads of a batch claim its states a chunk at a time, about CHUNK_WORK body-states
 * (~25 us) in a multiple of 8 states (the widest SIMD lanes): a thread that a busy machine
 * holds back leaves the rest to the others, and the lanes group the same states whatever
 * the thread count. Each thread starts in a block of its own, so that the threads write
 * their results to pages apart: two threads that first touch the same page of a new result
 * array (a 2 MB page, as numpy asks for) each have the kernel clear it, one in vain, and
 * wait for each other. */
#define CHUNK_WORK 1024

#if !defined(_WIN32) && (defined(__GNUC__) || defined(__clang__))
#define THREADED 1
#define ATOMIC_ADD(p, x) __atomic_add_fetch((p), (x), __ATOMIC_ACQ_REL)
#else
#define ATOMIC_ADD(p, x) (*(p) += (x))     /* one thread: run_batch starts no other */
#endif

/* One batch as its threads share it: the states [0, N) in T blocks, block t's states
 * [t N / T, (t + 1) N / T) (rounded to the chunks) claimed chunk by chunk. The caller
 * waits until every state is done, not for the threads: a thread that a busy machine starts
 * late finds nothing left and ends; the last thread out frees this. */
typedef struct {
    Slice job;
    Py_ssize_t N, chunk;
    long T;                              /* blocks: the threads asked for */
    Py_ssize_t next[MAX_THREADS];        /* the first state of each block not claimed yet */
    Py_ssize_t end[MAX_THREADS];         /* each block's end */
    long started;                        /* threads that took a block, in the order they start */
    Py_ssize_t done;                     /* states finished */
    int failed;                          /* chunks left undone (no memory for a scratch) */
    int refs;                            /* threads (the caller's included) holding this */
#ifdef THREADED
    pthread_mutex_t lock;
    pthread_cond_t finished;
#endif
} Batch;

/* Claim chunks of b, its own block's first, then those left in the blocks after it, until
 * none is left, and count them done (a chunk without memory too: then b->failed). The
 * thread that finishes the last state wakes the caller. */
static void
run_chunks(Batch *b)
{
    const Slice *s = &b->job;
    const long rows = s->rows;
    const long own = (ATOMIC_ADD(&b->started, 1) - 1) % b->T;
    double *work = malloc(sizeof(double) * work_size(s->kernel, rows, s->nv));
    for (long t = own, left = b->T; left > 0;) {
        Py_ssize_t lo = ATOMIC_ADD(&b->next[t], b->chunk) - b->chunk;
        if (lo >= b->end[t]) {
            t = (t + 1) % b->T;     /* this block is claimed: the next one's chunks */
            left--;
            continue;
        }
        Py_ssize_t hi = b->end[t] - lo < b->chunk ? b->end[t] : lo + b->chunk;
        if (run_states(s, work, lo, hi) < 0)
            ATOMIC_ADD(&b->failed, 1);
        if (ATOMIC_ADD(&b->done, hi - lo) == b->N) {
#ifdef THREADED
            pthread_mutex_lock(&b->lock);
            pthread_cond_broadcast(&b->finished);
            pthread_mutex_unlock(&b->lock);
#endif
        }
    }
    free(work);
}

/* Let go of b; the last thread frees it. */
static void
release_batch(Batch *b)
{
    if (ATOMIC_ADD(&b->refs, -1) == 0) {
#ifdef THREADED
        pthread_mutex_destroy(&b->lock);
        pthread_cond_destroy(&b->finished);
#endif
        free(b);
    }
}

#ifdef THREADED
static void *
run_thread(void *arg)
{
    run_chunks((Batch *)arg);
    release_batch((Batch *)arg);
    return NULL;
}
#endif

/* Run states [0, N) of `job` on up to `threads` threads (the caller's included). */
int
run_batch(const Slice *job, Py_ssize_t N, long threads)
{
    long T = threads < 1 ? 1 : (threads > MAX_THREADS ? MAX_THREADS : threads);
    Py_ssize_t most = N * job->rows / MIN_WORK;
    if (T > most)
        T = most > 0 ? (long)most : 1;
    Batch *b = calloc(1, sizeof(Batch));
    if (b == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    b->job = *job;
    b->N = N;
    b->chunk = (CHUNK_WORK / job->rows + 7) / 8 * 8;
    if (b->chunk < 8)
        b->chunk = 8;
    b->T = T;
    for (long t = 0; t < T; t++) {     /* block t: its share of the chunks */
        const Py_ssize_t chunks = (N + b->chunk - 1) / b->chunk;
        b->next[t] = chunks * t / T * b->chunk;
        b->end[t] = t + 1 < T ? chunks * (t + 1) / T * b->chunk : N;
    }
    b->refs = 1;
    int failed;
    Py_BEGIN_ALLOW_THREADS
#ifdef THREADED
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->finished, NULL);
    pthread_attr_t attr;
    int detached = T > 1 && pthread_attr_init(&attr) == 0;
    if (detached && pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED) != 0) {
        pthread_attr_destroy(&attr);
        detached = 0;
    }
    for (long t = 1; detached && t < T; t++) {
        pthread_t id;
        ATOMIC_ADD(&b->refs, 1);
        if (pthread_create(&id, &attr, run_thread, b) != 0) {
            ATOMIC_ADD(&b->refs, -1);   /* no thread to be had: the others take its part */
            break;
        }
    }
    if (detached)
        pthread_attr_destroy(&attr);
#endif
    run_chunks(b);
#ifdef THREADED
    pthread_mutex_lock(&b->lock);
    while (__atomic_load_n(&b->done, __ATOMIC_ACQUIRE) < N)
        pthread_cond_wait(&b->finished, &b->lock);
    pthread_mutex_unlock(&b->lock);
#endif
    failed = b->failed;
    release_batch(b);
    Py_END_ALLOW_THREADS
    if (failed) {
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}


/* Add the thread limits of a batch to the module m. */
int
threads_add(PyObject *m)
{
    if (PyModule_AddIntConstant(m, "MAX_THREADS", MAX_THREADS) < 0
            || PyModule_AddIntConstant(m, "MIN_WORK", MIN_WORK) < 0)
        return -1;
    return 0;
}
