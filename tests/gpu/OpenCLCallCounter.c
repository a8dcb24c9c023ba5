/*
 * An interposer of the OpenCL calls through which a host can wait for the device, or queue work on
 * it, counting them; every call is forwarded to the real libOpenCL.so.1. Linked into a test program
 * (tests/gpu/TestOpenCLCallCounts.cpp), it is in the program's global symbol scope, ahead of the
 * libOpenCL.so.1 that OpenMM's OpenCL plugin loads, so that every such call made by OpenMM or by the
 * plugins is counted. Every OpenCL 3.0 entry point that can make the host wait is here: the
 * read, write and map of buffers (and rectangles of them), the read, write and map of images, SVM
 * copies and maps, clFinish and clWaitForEvents; so no read can go round the count.
 *
 * Waits are split by what the device has queued after the point waited for:
 *   - a stall: a blocking read, write, copy or map, clFinish, or a wait for an event after which no
 *     kernel was queued (the device idles once it is reached, until the host queues more);
 *   - an overlapped wait: a wait for an event after which kernels were queued (OpenMM's idiom: the
 *     neighbour-list count, waited for once the force kernels are queued).
 */
#define CL_TARGET_OPENCL_VERSION 300
#define CL_USE_DEPRECATED_OPENCL_1_2_APIS
#include <CL/cl.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

/** The counts since the last reset; see openclCallCounts(). */
typedef struct {
    long stalls;            /* waits after which the device has nothing queued */
    long overlappedWaits;   /* waits for an event with kernels queued after it */
    long blockingReads;     /* blocking clEnqueueRead*, clEnqueueMap* (included in stalls) */
    long blockingWrites;    /* blocking clEnqueueWrite* (included in stalls) */
    long finishes;          /* clFinish (included in stalls) */
    long kernelLaunches;    /* clEnqueueNDRangeKernel, clEnqueueTask */
    long transfers;         /* clEnqueueRead/Write/Copy/Fill/Map*, blocking or not */
} OpenCLCallCounts;

static OpenCLCallCounts counts;
/* Kernels queued so far (never reset), and for a few recent events the value when each was made. */
static long launchesEver = 0;
#define TRACKED_EVENTS 64
static cl_event trackedEvent[TRACKED_EVENTS];
static long trackedLaunches[TRACKED_EVENTS];
static int nextTracked = 0;

OpenCLCallCounts openclCallCounts(void) {
    return counts;
}

void openclCallCountsReset(void) {
    OpenCLCallCounts zero = {0, 0, 0, 0, 0, 0, 0};
    counts = zero;
}

static void* real(const char* name) {
    static void* library = NULL;
    void* function;
    if (library == NULL)
        library = dlopen("libOpenCL.so.1", RTLD_NOW | RTLD_LOCAL);
    function = (library != NULL ? dlsym(library, name) : NULL);
    if (function == NULL) {
        fprintf(stderr, "OpenCLCallCounter: no %s in libOpenCL.so.1\n", name);
        abort();
    }
    return function;
}

static void track(cl_event* event) {
    if (event == NULL)
        return;
    trackedEvent[nextTracked] = *event;
    trackedLaunches[nextTracked] = launchesEver;
    nextTracked = (nextTracked + 1) % TRACKED_EVENTS;
}

/* An event not among the recent ones counts as a stall (the strict reading). */
static int kernelsQueuedAfter(cl_event event) {
    int i;
    for (i = 0; i < TRACKED_EVENTS; i++)
        if (trackedEvent[i] == event && event != NULL)
            return launchesEver > trackedLaunches[i];
    return 0;
}

static void blocking(cl_bool isBlocking, long* kind) {
    counts.transfers++;
    if (isBlocking) {
        counts.stalls++;
        (*kind)++;
    }
}

#define FORWARD(name, ...) ((name##_fn) real(#name))(__VA_ARGS__)

typedef cl_int (CL_API_CALL *clEnqueueNDRangeKernel_fn)(cl_command_queue, cl_kernel, cl_uint, const size_t*, const size_t*,
        const size_t*, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueNDRangeKernel(cl_command_queue queue, cl_kernel kernel, cl_uint dimensions,
        const size_t* offset, const size_t* global, const size_t* local, cl_uint numEvents, const cl_event* waitList,
        cl_event* event) {
    cl_int result = FORWARD(clEnqueueNDRangeKernel, queue, kernel, dimensions, offset, global, local, numEvents, waitList, event);
    counts.kernelLaunches++;
    launchesEver++;
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueTask_fn)(cl_command_queue, cl_kernel, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueTask(cl_command_queue queue, cl_kernel kernel, cl_uint numEvents, const cl_event* waitList,
        cl_event* event) {
    cl_int result = FORWARD(clEnqueueTask, queue, kernel, numEvents, waitList, event);
    counts.kernelLaunches++;
    launchesEver++;
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueReadBuffer_fn)(cl_command_queue, cl_mem, cl_bool, size_t, size_t, void*, cl_uint,
        const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueReadBuffer(cl_command_queue queue, cl_mem buffer, cl_bool isBlocking, size_t offset,
        size_t size, void* data, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingReads);
    cl_int result = FORWARD(clEnqueueReadBuffer, queue, buffer, isBlocking, offset, size, data, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueReadBufferRect_fn)(cl_command_queue, cl_mem, cl_bool, const size_t*, const size_t*,
        const size_t*, size_t, size_t, size_t, size_t, void*, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueReadBufferRect(cl_command_queue queue, cl_mem buffer, cl_bool isBlocking,
        const size_t* bufferOrigin, const size_t* hostOrigin, const size_t* region, size_t bufferRowPitch,
        size_t bufferSlicePitch, size_t hostRowPitch, size_t hostSlicePitch, void* data, cl_uint numEvents,
        const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingReads);
    cl_int result = FORWARD(clEnqueueReadBufferRect, queue, buffer, isBlocking, bufferOrigin, hostOrigin, region, bufferRowPitch,
                            bufferSlicePitch, hostRowPitch, hostSlicePitch, data, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueWriteBuffer_fn)(cl_command_queue, cl_mem, cl_bool, size_t, size_t, const void*, cl_uint,
        const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueWriteBuffer(cl_command_queue queue, cl_mem buffer, cl_bool isBlocking, size_t offset,
        size_t size, const void* data, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingWrites);
    cl_int result = FORWARD(clEnqueueWriteBuffer, queue, buffer, isBlocking, offset, size, data, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueWriteBufferRect_fn)(cl_command_queue, cl_mem, cl_bool, const size_t*, const size_t*,
        const size_t*, size_t, size_t, size_t, size_t, const void*, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueWriteBufferRect(cl_command_queue queue, cl_mem buffer, cl_bool isBlocking,
        const size_t* bufferOrigin, const size_t* hostOrigin, const size_t* region, size_t bufferRowPitch,
        size_t bufferSlicePitch, size_t hostRowPitch, size_t hostSlicePitch, const void* data, cl_uint numEvents,
        const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingWrites);
    cl_int result = FORWARD(clEnqueueWriteBufferRect, queue, buffer, isBlocking, bufferOrigin, hostOrigin, region, bufferRowPitch,
                            bufferSlicePitch, hostRowPitch, hostSlicePitch, data, numEvents, waitList, event);
    track(event);
    return result;
}

typedef void* (CL_API_CALL *clEnqueueMapBuffer_fn)(cl_command_queue, cl_mem, cl_bool, cl_map_flags, size_t, size_t, cl_uint,
        const cl_event*, cl_event*, cl_int*);
CL_API_ENTRY void* CL_API_CALL clEnqueueMapBuffer(cl_command_queue queue, cl_mem buffer, cl_bool isBlocking, cl_map_flags flags,
        size_t offset, size_t size, cl_uint numEvents, const cl_event* waitList, cl_event* event, cl_int* error) {
    blocking(isBlocking, &counts.blockingReads);
    void* result = FORWARD(clEnqueueMapBuffer, queue, buffer, isBlocking, flags, offset, size, numEvents, waitList, event, error);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueCopyBuffer_fn)(cl_command_queue, cl_mem, cl_mem, size_t, size_t, size_t, cl_uint,
        const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueCopyBuffer(cl_command_queue queue, cl_mem source, cl_mem destination, size_t sourceOffset,
        size_t destinationOffset, size_t size, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    counts.transfers++;
    cl_int result = FORWARD(clEnqueueCopyBuffer, queue, source, destination, sourceOffset, destinationOffset, size, numEvents,
                            waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueFillBuffer_fn)(cl_command_queue, cl_mem, const void*, size_t, size_t, size_t, cl_uint,
        const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueFillBuffer(cl_command_queue queue, cl_mem buffer, const void* pattern, size_t patternSize,
        size_t offset, size_t size, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    counts.transfers++;
    cl_int result = FORWARD(clEnqueueFillBuffer, queue, buffer, pattern, patternSize, offset, size, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueMarkerWithWaitList_fn)(cl_command_queue, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueMarkerWithWaitList(cl_command_queue queue, cl_uint numEvents, const cl_event* waitList,
        cl_event* event) {
    cl_int result = FORWARD(clEnqueueMarkerWithWaitList, queue, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueMarker_fn)(cl_command_queue, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueMarker(cl_command_queue queue, cl_event* event) {
    cl_int result = FORWARD(clEnqueueMarker, queue, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clFinish_fn)(cl_command_queue);
CL_API_ENTRY cl_int CL_API_CALL clFinish(cl_command_queue queue) {
    counts.stalls++;
    counts.finishes++;
    return FORWARD(clFinish, queue);
}

typedef cl_int (CL_API_CALL *clWaitForEvents_fn)(cl_uint, const cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clWaitForEvents(cl_uint numEvents, const cl_event* events) {
    cl_uint i;
    int overlapped = numEvents > 0;
    for (i = 0; i < numEvents; i++)
        overlapped = overlapped && kernelsQueuedAfter(events[i]);
    if (overlapped)
        counts.overlappedWaits++;
    else
        counts.stalls++;
    return FORWARD(clWaitForEvents, numEvents, events);
}

/* Blocking calls that OpenMM 8.6.1 does not make, counted all the same, so that a future use cannot go unseen. */
typedef cl_int (CL_API_CALL *clEnqueueReadImage_fn)(cl_command_queue, cl_mem, cl_bool, const size_t*, const size_t*, size_t,
        size_t, void*, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueReadImage(cl_command_queue queue, cl_mem image, cl_bool isBlocking, const size_t* origin,
        const size_t* region, size_t rowPitch, size_t slicePitch, void* data, cl_uint numEvents, const cl_event* waitList,
        cl_event* event) {
    blocking(isBlocking, &counts.blockingReads);
    cl_int result = FORWARD(clEnqueueReadImage, queue, image, isBlocking, origin, region, rowPitch, slicePitch, data, numEvents,
                            waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueSVMMemcpy_fn)(cl_command_queue, cl_bool, void*, const void*, size_t, cl_uint, const cl_event*,
        cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueSVMMemcpy(cl_command_queue queue, cl_bool isBlocking, void* destination, const void* source,
        size_t size, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingReads);
    cl_int result = FORWARD(clEnqueueSVMMemcpy, queue, isBlocking, destination, source, size, numEvents, waitList, event);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueWriteImage_fn)(cl_command_queue, cl_mem, cl_bool, const size_t*, const size_t*, size_t,
        size_t, const void*, cl_uint, const cl_event*, cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueWriteImage(cl_command_queue queue, cl_mem image, cl_bool isBlocking, const size_t* origin,
        const size_t* region, size_t rowPitch, size_t slicePitch, const void* data, cl_uint numEvents, const cl_event* waitList,
        cl_event* event) {
    blocking(isBlocking, &counts.blockingWrites);
    cl_int result = FORWARD(clEnqueueWriteImage, queue, image, isBlocking, origin, region, rowPitch, slicePitch, data, numEvents,
                            waitList, event);
    track(event);
    return result;
}

typedef void* (CL_API_CALL *clEnqueueMapImage_fn)(cl_command_queue, cl_mem, cl_bool, cl_map_flags, const size_t*, const size_t*,
        size_t*, size_t*, cl_uint, const cl_event*, cl_event*, cl_int*);
CL_API_ENTRY void* CL_API_CALL clEnqueueMapImage(cl_command_queue queue, cl_mem image, cl_bool isBlocking, cl_map_flags flags,
        const size_t* origin, const size_t* region, size_t* rowPitch, size_t* slicePitch, cl_uint numEvents,
        const cl_event* waitList, cl_event* event, cl_int* error) {
    blocking(isBlocking, &counts.blockingReads);
    void* result = FORWARD(clEnqueueMapImage, queue, image, isBlocking, flags, origin, region, rowPitch, slicePitch, numEvents,
                           waitList, event, error);
    track(event);
    return result;
}

typedef cl_int (CL_API_CALL *clEnqueueSVMMap_fn)(cl_command_queue, cl_bool, cl_map_flags, void*, size_t, cl_uint, const cl_event*,
        cl_event*);
CL_API_ENTRY cl_int CL_API_CALL clEnqueueSVMMap(cl_command_queue queue, cl_bool isBlocking, cl_map_flags flags, void* memory,
        size_t size, cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    blocking(isBlocking, &counts.blockingReads);
    cl_int result = FORWARD(clEnqueueSVMMap, queue, isBlocking, flags, memory, size, numEvents, waitList, event);
    track(event);
    return result;
}
