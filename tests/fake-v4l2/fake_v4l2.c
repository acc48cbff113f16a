/*
 * fake_v4l2: an LD_PRELOAD stand-in for one V4L2 capture device, used by tests/camera.rs.
 *
 * It answers the calls the `v4l` crate (0.14, v4l2-sys backend) makes for a single device path:
 * open/open64/openat/openat64, close, ioctl and syscall(SYS_ioctl) (the crate calls ioctl through
 * libc::syscall), mmap/mmap64 and poll. Everything else, and every other path or fd, goes to the
 * real libc through dlsym(RTLD_NEXT). munmap needs no interception: the buffers handed out by the
 * fake mmap are real anonymous mappings of exactly the queried length.
 *
 * Configuration (environment, read once at load):
 *   FAKE_V4L2_DEVICE        path to answer for (required; without it nothing is intercepted)
 *   FAKE_V4L2_FORMAT        comma list of fourccs: YUYV,NV12,MJPG,RGB3,BGR3,GREY (default YUYV)
 *   FAKE_V4L2_SIZE          comma list of WxH (default 640x480)
 *   FAKE_V4L2_FPS           comma list of frame rates (default 30)
 *   FAKE_V4L2_FRAMES        colon list of files, each the raw bytes of one frame; frame k is
 *                           file k mod n (default: a pattern that changes every frame)
 *   FAKE_V4L2_VANISH_AFTER  after N delivered frames the device disappears (ENODEV, POLLERR)
 *   FAKE_V4L2_RETURN_AFTER_MS  and can be opened again this long after (default 500)
 *   FAKE_V4L2_NO_FRAMES     if 1, the device streams but never delivers a frame
 *   FAKE_V4L2_NO_CONTROLS   if set, the device has no controls (else exposure, white balance, gain)
 *   FAKE_V4L2_BUSY_FOR_MS   setting a format fails with EBUSY for this long after start, as
 *                           when another program is capturing from the device
 *   FAKE_V4L2_CARD          card name (default "Fake V4L2 camera")
 *   FAKE_V4L2_OPEN_DELAY_MS each open of the device takes this long (a slow USB camera)
 *   FAKE_V4L2_ABSENT_FOR_MS opening the device fails with ENOENT for this long after start
 *                           (a camera plugged in after the app started)
 *   FAKE_V4L2_LOG           file to which each open and close of the device is appended, as
 *                           "open MS" / "close MS" lines (MS: wall-clock milliseconds since 1970),
 *                           with "opening MS" where a slow open starts
 *
 * Not modelled: read() I/O, USERPTR/DMABUF memory, controls, multi-planar API, select().
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#define MAX_LIST 16
#define MAX_BUFS 8
#define MAX_FDS 4096

static int (*real_open)(const char *, int, ...);
static int (*real_open64)(const char *, int, ...);
static int (*real_openat)(int, const char *, int, ...);
static int (*real_openat64)(int, const char *, int, ...);
static int (*real_close)(int);
static int (*real_ioctl)(int, unsigned long, ...);
static long (*real_syscall)(long, ...);
static void *(*real_mmap)(void *, size_t, int, int, int, off_t);
static void *(*real_mmap64)(void *, size_t, int, int, int, off_t);
static int (*real_poll)(struct pollfd *, nfds_t, int);

struct buffer {
	void *mem;
	size_t length;
	int queued;
	int handed_out; /* mmapped by the app: the app's munmap frees it */
	uint64_t queue_order;
};

static struct {
	char path[512];
	char card[32];
	uint32_t formats[MAX_LIST];
	int n_formats;
	uint32_t widths[MAX_LIST], heights[MAX_LIST];
	int n_sizes;
	uint32_t fps[MAX_LIST];
	int n_fps;
	char *frame_files[64];
	int n_frame_files;
	long vanish_after;
	long return_after_ms;
	uint64_t busy_until_ns;
	uint64_t absent_until_ns;
	long open_delay_ms;
	const char *log;
	int no_frames;
} cfg;

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static volatile unsigned char fake_fd[MAX_FDS];
static struct {
	uint32_t format, width, height, fps;
	struct buffer bufs[MAX_BUFS];
	int n_bufs;
	int owner_fd; /* the fd that requested the buffers */
	int streaming;
	uint64_t next_due_ns;
	uint64_t queue_counter;
	uint32_t sequence;
	long delivered;
	int vanished;      /* open fds are dead */
	int vanished_once; /* the vanish happens once per process */
	uint64_t vanished_at_ns;
} dev;

static uint64_t now_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

static void sleep_ns(uint64_t ns)
{
	struct timespec ts = {(time_t)(ns / 1000000000ull), (long)(ns % 1000000000ull)};
	while (nanosleep(&ts, &ts) == -1 && errno == EINTR) {
	}
}

static uint32_t fourcc_of(const char *s)
{
	return (uint32_t)s[0] | (uint32_t)s[1] << 8 | (uint32_t)s[2] << 16 | (uint32_t)s[3] << 24;
}

static void parse_config(void)
{
	const char *e = getenv("FAKE_V4L2_DEVICE");
	if (!e)
		return;
	snprintf(cfg.path, sizeof cfg.path, "%s", e);
	e = getenv("FAKE_V4L2_CARD");
	snprintf(cfg.card, sizeof cfg.card, "%s", e ? e : "Fake V4L2 camera");

	char buf[4096];
	e = getenv("FAKE_V4L2_FORMAT");
	snprintf(buf, sizeof buf, "%s", e ? e : "YUYV");
	for (char *t = strtok(buf, ","); t && cfg.n_formats < MAX_LIST; t = strtok(NULL, ","))
		if (strlen(t) == 4)
			cfg.formats[cfg.n_formats++] = fourcc_of(t);

	e = getenv("FAKE_V4L2_SIZE");
	snprintf(buf, sizeof buf, "%s", e ? e : "640x480");
	for (char *t = strtok(buf, ","); t && cfg.n_sizes < MAX_LIST; t = strtok(NULL, ","))
		if (sscanf(t, "%ux%u", &cfg.widths[cfg.n_sizes], &cfg.heights[cfg.n_sizes]) == 2)
			cfg.n_sizes++;

	e = getenv("FAKE_V4L2_FPS");
	snprintf(buf, sizeof buf, "%s", e ? e : "30");
	for (char *t = strtok(buf, ","); t && cfg.n_fps < MAX_LIST; t = strtok(NULL, ","))
		if (atoi(t) > 0)
			cfg.fps[cfg.n_fps++] = (uint32_t)atoi(t);

	e = getenv("FAKE_V4L2_FRAMES");
	if (e && *e) {
		char *copy = strdup(e);
		for (char *t = strtok(copy, ":"); t && cfg.n_frame_files < 64; t = strtok(NULL, ":"))
			cfg.frame_files[cfg.n_frame_files++] = t;
	}
	e = getenv("FAKE_V4L2_VANISH_AFTER");
	cfg.vanish_after = e ? atol(e) : 0;
	e = getenv("FAKE_V4L2_RETURN_AFTER_MS");
	cfg.return_after_ms = e ? atol(e) : 500;
	e = getenv("FAKE_V4L2_BUSY_FOR_MS");
	cfg.busy_until_ns = e ? now_ns() + (uint64_t)atol(e) * 1000000ull : 0;
	e = getenv("FAKE_V4L2_ABSENT_FOR_MS");
	cfg.absent_until_ns = e ? now_ns() + (uint64_t)atol(e) * 1000000ull : 0;
	e = getenv("FAKE_V4L2_OPEN_DELAY_MS");
	cfg.open_delay_ms = e ? atol(e) : 0;
	cfg.log = getenv("FAKE_V4L2_LOG");
	e = getenv("FAKE_V4L2_NO_FRAMES");
	cfg.no_frames = e && atoi(e) == 1;

	dev.format = cfg.formats[0];
	dev.width = cfg.widths[0];
	dev.height = cfg.heights[0];
	dev.fps = cfg.fps[0];
}

__attribute__((constructor)) static void fake_init(void)
{
	real_open = dlsym(RTLD_NEXT, "open");
	real_open64 = dlsym(RTLD_NEXT, "open64");
	real_openat = dlsym(RTLD_NEXT, "openat");
	real_openat64 = dlsym(RTLD_NEXT, "openat64");
	real_close = dlsym(RTLD_NEXT, "close");
	real_ioctl = dlsym(RTLD_NEXT, "ioctl");
	real_syscall = dlsym(RTLD_NEXT, "syscall");
	real_mmap = dlsym(RTLD_NEXT, "mmap");
	real_mmap64 = dlsym(RTLD_NEXT, "mmap64");
	real_poll = dlsym(RTLD_NEXT, "poll");
	parse_config();
}

static int is_fake(int fd)
{
	return cfg.path[0] && fd >= 0 && fd < MAX_FDS && fake_fd[fd];
}

/* The device's path, or a link to it (as /dev/v4l/by-id/... are). */
static int is_fake_path(const char *path)
{
	if (!cfg.path[0] || !path)
		return 0;
	if (strcmp(path, cfg.path) == 0)
		return 1;
	char a[PATH_MAX], b[PATH_MAX];
	return realpath(path, a) && realpath(cfg.path, b) && strcmp(a, b) == 0;
}

/* Bytes in one frame of the given format; MJPEG gets a generous upper bound like real drivers. */
static size_t frame_size(uint32_t f, uint32_t w, uint32_t h)
{
	switch (f) {
	case V4L2_PIX_FMT_NV12:
		return (size_t)w * h * 3 / 2;
	case V4L2_PIX_FMT_RGB24:
	case V4L2_PIX_FMT_BGR24:
		return (size_t)w * h * 3;
	case V4L2_PIX_FMT_GREY:
		return (size_t)w * h;
	default: /* YUYV, MJPG */
		return (size_t)w * h * 2;
	}
}

static uint32_t bytes_per_line(uint32_t f, uint32_t w)
{
	switch (f) {
	case V4L2_PIX_FMT_NV12:
	case V4L2_PIX_FMT_GREY:
		return w;
	case V4L2_PIX_FMT_RGB24:
	case V4L2_PIX_FMT_BGR24:
		return w * 3;
	case V4L2_PIX_FMT_MJPEG:
		return 0;
	default:
		return w * 2;
	}
}

/* The vanished device comes back (can be opened again) after return_after_ms. */
static int device_present(void)
{
	if (now_ns() < cfg.absent_until_ns)
		return 0;
	if (!dev.vanished)
		return 1;
	return now_ns() - dev.vanished_at_ns >= (uint64_t)cfg.return_after_ms * 1000000ull;
}

static void free_buffers(void);

/* Appends "WHAT MS" to FAKE_V4L2_LOG, if set. */
static void log_event(const char *what)
{
	if (!cfg.log)
		return;
	struct timespec t;
	clock_gettime(CLOCK_REALTIME, &t);
	int fd = real_open(cfg.log, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
	if (fd < 0)
		return;
	char line[64];
	int n = snprintf(line, sizeof line, "%s %lld\n", what,
			 (long long)t.tv_sec * 1000 + t.tv_nsec / 1000000);
	if (write(fd, line, (size_t)n) < 0)
		n = 0;
	real_close(fd);
}

static int open_fake(void)
{
	if (cfg.open_delay_ms > 0) {
		log_event("opening");
		struct timespec d = {cfg.open_delay_ms / 1000, (cfg.open_delay_ms % 1000) * 1000000};
		nanosleep(&d, NULL);
	}
	pthread_mutex_lock(&lock);
	if (!device_present()) {
		pthread_mutex_unlock(&lock);
		errno = ENOENT;
		return -1;
	}
	if (dev.vanished) {
		/* Back again: a fresh device. Fds opened before the vanish stay dead. */
		dev.vanished = 0;
		dev.streaming = 0;
		free_buffers();
		for (int i = 0; i < MAX_FDS; i++)
			if (fake_fd[i] == 2)
				fake_fd[i] = 3;
	}
	pthread_mutex_unlock(&lock);
	int fd = real_open("/dev/null", O_RDWR | O_CLOEXEC);
	if (fd >= 0 && fd < MAX_FDS)
		fake_fd[fd] = 1;
	if (fd >= 0)
		log_event("open");
	return fd;
}

/* fake_fd: 1 = live, 2 = the device vanished under it, 3 = stale fd from before a vanish. */
static int fd_dead(int fd)
{
	return fake_fd[fd] != 1;
}

static int pick_mode_size(uint32_t w, uint32_t h)
{
	for (int i = 0; i < cfg.n_sizes; i++)
		if (cfg.widths[i] == w && cfg.heights[i] == h)
			return i;
	return 0;
}

static int has_format(uint32_t f)
{
	for (int i = 0; i < cfg.n_formats; i++)
		if (cfg.formats[i] == f)
			return 1;
	return 0;
}

static void fill_pix(struct v4l2_pix_format *p, uint32_t f, uint32_t w, uint32_t h)
{
	memset(p, 0, sizeof *p);
	p->width = w;
	p->height = h;
	p->pixelformat = f;
	p->field = V4L2_FIELD_NONE;
	p->bytesperline = bytes_per_line(f, w);
	p->sizeimage = (uint32_t)frame_size(f, w, h);
	p->colorspace = f == V4L2_PIX_FMT_MJPEG ? V4L2_COLORSPACE_JPEG : V4L2_COLORSPACE_SRGB;
}

static void free_buffers(void)
{
	for (int i = 0; i < dev.n_bufs; i++)
		if (!dev.bufs[i].handed_out)
			munmap(dev.bufs[i].mem, dev.bufs[i].length);
	dev.n_bufs = 0;
	dev.streaming = 0;
}

static int reqbufs(int fd, struct v4l2_requestbuffers *r)
{
	if (r->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || r->memory != V4L2_MEMORY_MMAP)
		return EINVAL;
	if (dev.streaming)
		return EBUSY;
	free_buffers();
	uint32_t n = r->count;
	if (n == 0)
		return 0;
	if (n < 2)
		n = 2;
	if (n > MAX_BUFS)
		n = MAX_BUFS;
	size_t len = frame_size(dev.format, dev.width, dev.height);
	for (uint32_t i = 0; i < n; i++) {
		void *m = real_mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
		if (m == MAP_FAILED)
			return ENOMEM;
		dev.bufs[i] = (struct buffer){.mem = m, .length = len};
	}
	dev.n_bufs = (int)n;
	dev.owner_fd = fd;
	r->count = n;
	r->capabilities = V4L2_BUF_CAP_SUPPORTS_MMAP;
	return 0;
}

static void describe_buffer(struct v4l2_buffer *b, int i)
{
	b->index = (uint32_t)i;
	b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	b->memory = V4L2_MEMORY_MMAP;
	b->length = (uint32_t)dev.bufs[i].length;
	b->m.offset = (uint32_t)i * 0x100000u;
	b->field = V4L2_FIELD_NONE;
	b->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | (dev.bufs[i].queued ? V4L2_BUF_FLAG_QUEUED : 0);
}

/* Copies frame `seq` into `dst`; returns the bytes used. */
static size_t fill_frame(unsigned char *dst, size_t cap, uint32_t seq)
{
	if (cfg.n_frame_files == 0) {
		for (size_t i = 0; i < cap; i++)
			dst[i] = (unsigned char)(seq * 16u + i / 4096u);
		return cap;
	}
	const char *file = cfg.frame_files[seq % (uint32_t)cfg.n_frame_files];
	FILE *f = fopen(file, "rb");
	if (!f)
		return 0;
	size_t n = fread(dst, 1, cap, f);
	fclose(f);
	return n;
}

/* A queued buffer is ready once the frame interval has passed. */
static int frame_ready(void)
{
	if (!dev.streaming || cfg.no_frames)
		return 0;
	for (int i = 0; i < dev.n_bufs; i++)
		if (dev.bufs[i].queued)
			return now_ns() >= dev.next_due_ns;
	return 0;
}

static int dqbuf(struct v4l2_buffer *b)
{
	if (!dev.streaming)
		return EINVAL;
	if (!frame_ready())
		return EAGAIN;
	int best = -1;
	for (int i = 0; i < dev.n_bufs; i++)
		if (dev.bufs[i].queued &&
		    (best < 0 || dev.bufs[i].queue_order < dev.bufs[best].queue_order))
			best = i;
	struct buffer *buf = &dev.bufs[best];
	uint64_t t = now_ns();
	size_t used = fill_frame(buf->mem, buf->length, dev.sequence);
	buf->queued = 0;
	describe_buffer(b, best);
	b->bytesused = (uint32_t)used;
	b->sequence = dev.sequence++;
	b->timestamp.tv_sec = (time_t)(t / 1000000000ull);
	b->timestamp.tv_usec = (long)(t % 1000000000ull / 1000ull);
	dev.next_due_ns += 1000000000ull / dev.fps;
	if (dev.next_due_ns < t)
		dev.next_due_ns = t; /* a slow reader drops frames rather than bursting */
	dev.delivered++;
	if (cfg.vanish_after > 0 && dev.delivered == cfg.vanish_after && !dev.vanished_once) {
		dev.vanished = dev.vanished_once = 1;
		dev.vanished_at_ns = now_ns();
		dev.streaming = 0;
		for (int i = 0; i < MAX_FDS; i++)
			if (fake_fd[i] == 1)
				fake_fd[i] = 2;
	}
	return 0;
}

static int enum_fmt(struct v4l2_fmtdesc *d)
{
	if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= (uint32_t)cfg.n_formats)
		return EINVAL;
	uint32_t f = cfg.formats[d->index];
	d->pixelformat = f;
	d->flags = f == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
	snprintf((char *)d->description, sizeof d->description, "fake %.4s", (char *)&f);
	return 0;
}

static int enum_framesizes(struct v4l2_frmsizeenum *s)
{
	if (!has_format(s->pixel_format) || s->index >= (uint32_t)cfg.n_sizes)
		return EINVAL;
	s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
	s->discrete.width = cfg.widths[s->index];
	s->discrete.height = cfg.heights[s->index];
	return 0;
}

static int enum_frameintervals(struct v4l2_frmivalenum *v)
{
	if (!has_format(v->pixel_format) || v->index >= (uint32_t)cfg.n_fps)
		return EINVAL;
	int i = pick_mode_size(v->width, v->height);
	if (cfg.widths[i] != v->width || cfg.heights[i] != v->height)
		return EINVAL;
	v->type = V4L2_FRMIVAL_TYPE_DISCRETE;
	v->discrete.numerator = 1;
	v->discrete.denominator = cfg.fps[v->index];
	return 0;
}

static int set_fmt(struct v4l2_format *f, int apply)
{
	if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
		return EINVAL;
	if (apply && dev.n_bufs > 0)
		return EBUSY;
	/* Another process streams from the device for the first FAKE_V4L2_BUSY_FOR_MS. */
	if (apply && now_ns() < cfg.busy_until_ns)
		return EBUSY;
	struct v4l2_pix_format *p = &f->fmt.pix;
	uint32_t fmt = has_format(p->pixelformat) ? p->pixelformat : cfg.formats[0];
	int s = pick_mode_size(p->width, p->height);
	fill_pix(p, fmt, cfg.widths[s], cfg.heights[s]);
	if (apply) {
		dev.format = fmt;
		dev.width = cfg.widths[s];
		dev.height = cfg.heights[s];
	}
	return 0;
}

static int parm(struct v4l2_streamparm *p, int apply)
{
	if (p->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
		return EINVAL;
	struct v4l2_fract *tpf = &p->parm.capture.timeperframe;
	if (apply && tpf->numerator > 0 && tpf->denominator > 0) {
		/* The nearest advertised rate, as drivers do. */
		double want = (double)tpf->denominator / tpf->numerator;
		uint32_t best = cfg.fps[0];
		for (int i = 0; i < cfg.n_fps; i++)
			if (abs((int)cfg.fps[i] - (int)want) < abs((int)best - (int)want))
				best = cfg.fps[i];
		dev.fps = best;
	}
	memset(&p->parm.capture, 0, sizeof p->parm.capture);
	p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
	tpf->numerator = 1;
	tpf->denominator = dev.fps;
	return 0;
}

static int querycap(struct v4l2_capability *c)
{
	memset(c, 0, sizeof *c);
	snprintf((char *)c->driver, sizeof c->driver, "fake_v4l2");
	snprintf((char *)c->card, sizeof c->card, "%s", cfg.card);
	snprintf((char *)c->bus_info, sizeof c->bus_info, "fake:0");
	c->version = 0x00060100;
	c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
	c->capabilities = c->device_caps | V4L2_CAP_DEVICE_CAPS;
	return 0;
}

static int buffer_ioctl(int fd, unsigned long req, void *arg)
{
	struct v4l2_buffer *b = arg;
	switch (req) {
	case VIDIOC_REQBUFS:
		return reqbufs(fd, arg);
	case VIDIOC_QUERYBUF:
	case VIDIOC_QBUF:
		if (b->index >= (uint32_t)dev.n_bufs)
			return EINVAL;
		if (req == VIDIOC_QBUF) {
			if (dev.bufs[b->index].queued)
				return EINVAL; /* vb2 refuses a buffer that is already queued */
			dev.bufs[b->index].queued = 1;
			dev.bufs[b->index].queue_order = dev.queue_counter++;
		}
		describe_buffer(b, (int)b->index);
		return 0;
	case VIDIOC_DQBUF:
		return dqbuf(b);
	case VIDIOC_STREAMON:
		dev.streaming = 1;
		dev.next_due_ns = now_ns() + 1000000000ull / dev.fps;
		return 0;
	case VIDIOC_STREAMOFF:
		dev.streaming = 0;
		for (int i = 0; i < dev.n_bufs; i++)
			dev.bufs[i].queued = 0;
		return 0;
	}
	return ENOTTY;
}

/* Camera controls: auto exposure (a menu: 1 manual, 3 aperture priority), exposure time in
 * 100 us units, auto white balance, white balance temperature, gain. FAKE_V4L2_NO_CONTROLS=1
 * gives a camera without any. A value set is clamped to the range and rounded to the step. */
struct fake_ctrl {
	uint32_t id, type;
	const char *name;
	int32_t min, max, step, def, value;
};
static struct fake_ctrl ctrls[] = {
	{V4L2_CID_GAIN, V4L2_CTRL_TYPE_INTEGER, "Gain", 0, 255, 1, 32, 32},
	{V4L2_CID_AUTO_WHITE_BALANCE, V4L2_CTRL_TYPE_BOOLEAN, "White Balance, Automatic", 0, 1, 1, 1, 1},
	{V4L2_CID_WHITE_BALANCE_TEMPERATURE, V4L2_CTRL_TYPE_INTEGER, "White Balance Temperature", 2800, 6500, 10, 4600, 4600},
	{V4L2_CID_EXPOSURE_AUTO, V4L2_CTRL_TYPE_MENU, "Auto Exposure", 1, 3, 2, 3, 3},
	{V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CTRL_TYPE_INTEGER, "Exposure Time, Absolute", 3, 2047, 1, 156, 156},
};
#define N_CTRLS ((int)(sizeof ctrls / sizeof ctrls[0]))

static struct fake_ctrl *find_ctrl(uint32_t id)
{
	if (getenv("FAKE_V4L2_NO_CONTROLS"))
		return NULL;
	for (int i = 0; i < N_CTRLS; i++)
		if (ctrls[i].id == id)
			return &ctrls[i];
	return NULL;
}

static int query_ext_ctrl(struct v4l2_query_ext_ctrl *q)
{
	uint32_t flags = V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
	struct fake_ctrl *c = NULL;
	if (q->id & flags) {
		uint32_t after = q->id & ~flags;
		for (int i = 0; i < N_CTRLS && !getenv("FAKE_V4L2_NO_CONTROLS"); i++)
			if (ctrls[i].id > after && (!c || ctrls[i].id < c->id))
				c = &ctrls[i];
	} else {
		c = find_ctrl(q->id);
	}
	if (!c)
		return EINVAL;
	memset(q, 0, sizeof *q);
	q->id = c->id;
	q->type = c->type;
	snprintf(q->name, sizeof q->name, "%s", c->name);
	q->minimum = c->min;
	q->maximum = c->max;
	q->step = (uint64_t)c->step;
	q->default_value = c->def;
	q->elems = q->nr_of_dims = 0;
	q->elem_size = 4;
	q->elems = 1;
	return 0;
}

static int querymenu(struct v4l2_querymenu *m)
{
	if (m->id != V4L2_CID_EXPOSURE_AUTO || !find_ctrl(m->id))
		return EINVAL;
	const char *name = m->index == 1 ? "Manual Mode" : m->index == 3 ? "Aperture Priority Mode" : NULL;
	if (!name)
		return EINVAL;
	snprintf((char *)m->name, sizeof m->name, "%s", name);
	return 0;
}

static int ext_ctrls(struct v4l2_ext_controls *list, int set)
{
	for (uint32_t i = 0; i < list->count; i++) {
		struct v4l2_ext_control *x = &list->controls[i];
		struct fake_ctrl *c = find_ctrl(x->id);
		if (!c)
			return EINVAL;
		if (!set) {
			x->value = c->value;
			continue;
		}
		int32_t v = (int32_t)x->value64;
		if (v < c->min)
			v = c->min;
		if (v > c->max)
			v = c->max;
		v = c->min + (v - c->min) / c->step * c->step;
		c->value = v;
	}
	return 0;
}

/* Returns 0 or an errno value. */
static int handle_ioctl(int fd, unsigned long req, void *arg)
{
	if (fd_dead(fd))
		return ENODEV;
	switch (req) {
	case VIDIOC_QUERYCAP:
		return querycap(arg);
	case VIDIOC_ENUM_FMT:
		return enum_fmt(arg);
	case VIDIOC_ENUM_FRAMESIZES:
		return enum_framesizes(arg);
	case VIDIOC_ENUM_FRAMEINTERVALS:
		return enum_frameintervals(arg);
	case VIDIOC_G_FMT:
		if (((struct v4l2_format *)arg)->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
			return EINVAL;
		fill_pix(&((struct v4l2_format *)arg)->fmt.pix, dev.format, dev.width, dev.height);
		return 0;
	case VIDIOC_S_FMT:
		return set_fmt(arg, 1);
	case VIDIOC_TRY_FMT:
		return set_fmt(arg, 0);
	case VIDIOC_G_PARM:
		return parm(arg, 0);
	case VIDIOC_S_PARM:
		return parm(arg, 1);
	case VIDIOC_QUERY_EXT_CTRL:
		return query_ext_ctrl(arg);
	case VIDIOC_QUERYMENU:
		return querymenu(arg);
	case VIDIOC_G_EXT_CTRLS:
		return ext_ctrls(arg, 0);
	case VIDIOC_S_EXT_CTRLS:
		return ext_ctrls(arg, 1);
	}
	return buffer_ioctl(fd, req, arg);
}

static int fake_ioctl(int fd, unsigned long req, void *arg)
{
	pthread_mutex_lock(&lock);
	int err = handle_ioctl(fd, req, arg);
	pthread_mutex_unlock(&lock);
	if (err) {
		errno = err;
		return -1;
	}
	return 0;
}

int ioctl(int fd, unsigned long req, ...)
{
	va_list ap;
	va_start(ap, req);
	void *arg = va_arg(ap, void *);
	va_end(ap);
	if (is_fake(fd))
		return fake_ioctl(fd, req, arg);
	return real_ioctl(fd, req, arg);
}

long syscall(long number, ...)
{
	va_list ap;
	va_start(ap, number);
	long a[6];
	for (int i = 0; i < 6; i++)
		a[i] = va_arg(ap, long);
	va_end(ap);
	if (number == SYS_ioctl && is_fake((int)a[0]))
		return fake_ioctl((int)a[0], (unsigned long)a[1], (void *)a[2]);
	return real_syscall(number, a[0], a[1], a[2], a[3], a[4], a[5]);
}

static mode_t mode_arg(int flags, va_list ap)
{
	return (flags & (O_CREAT | O_TMPFILE)) ? va_arg(ap, mode_t) : 0;
}

int open(const char *path, int flags, ...)
{
	va_list ap;
	va_start(ap, flags);
	mode_t mode = mode_arg(flags, ap);
	va_end(ap);
	return is_fake_path(path) ? open_fake() : real_open(path, flags, mode);
}

int open64(const char *path, int flags, ...)
{
	va_list ap;
	va_start(ap, flags);
	mode_t mode = mode_arg(flags, ap);
	va_end(ap);
	return is_fake_path(path) ? open_fake() : real_open64(path, flags, mode);
}

int openat(int dirfd, const char *path, int flags, ...)
{
	va_list ap;
	va_start(ap, flags);
	mode_t mode = mode_arg(flags, ap);
	va_end(ap);
	return is_fake_path(path) ? open_fake() : real_openat(dirfd, path, flags, mode);
}

int openat64(int dirfd, const char *path, int flags, ...)
{
	va_list ap;
	va_start(ap, flags);
	mode_t mode = mode_arg(flags, ap);
	va_end(ap);
	return is_fake_path(path) ? open_fake() : real_openat64(dirfd, path, flags, mode);
}

int close(int fd)
{
	if (is_fake(fd)) {
		pthread_mutex_lock(&lock);
		/* Closing the fd that owns the buffers ends streaming, as in the kernel. */
		if (fake_fd[fd] == 1 && dev.n_bufs > 0 && dev.owner_fd == fd)
			free_buffers();
		fake_fd[fd] = 0;
		pthread_mutex_unlock(&lock);
		log_event("close");
	}
	return real_close(fd);
}

static void *fake_mmap(size_t len, int fd, off_t off)
{
	pthread_mutex_lock(&lock);
	void *r = MAP_FAILED;
	int i = (int)(off / 0x100000);
	if (fd_dead(fd))
		errno = ENODEV;
	else if (i < 0 || i >= dev.n_bufs || len != dev.bufs[i].length)
		errno = EINVAL;
	else {
		dev.bufs[i].handed_out = 1;
		r = dev.bufs[i].mem;
	}
	pthread_mutex_unlock(&lock);
	return r;
}

void *mmap(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
	if (is_fake(fd))
		return fake_mmap(len, fd, off);
	return real_mmap(addr, len, prot, flags, fd, off);
}

void *mmap64(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
	if (is_fake(fd))
		return fake_mmap(len, fd, off);
	return real_mmap64(addr, len, prot, flags, fd, off);
}

/* Waits like a driver: until the next frame is due, the timeout passes, or forever (-1). */
static int fake_poll(struct pollfd *p, int timeout_ms)
{
	uint64_t deadline = timeout_ms < 0 ? UINT64_MAX : now_ns() + (uint64_t)timeout_ms * 1000000ull;
	for (;;) {
		pthread_mutex_lock(&lock);
		int dead = fd_dead(p->fd), ready = !dead && frame_ready(), streaming = dev.streaming;
		uint64_t due = dev.next_due_ns;
		pthread_mutex_unlock(&lock);
		if (dead || !streaming) {
			p->revents = POLLERR | (dead ? POLLHUP : 0);
			return 1;
		}
		if (ready) {
			p->revents = POLLIN | POLLRDNORM;
			return 1;
		}
		uint64_t t = now_ns();
		if (t >= deadline) {
			p->revents = 0;
			return 0;
		}
		uint64_t wake = cfg.no_frames || due <= t ? t + 5000000ull : due;
		sleep_ns((wake < deadline ? wake : deadline) - t);
	}
}

/* glibc declares poll's array write-only; this wrapper reads fds[0].fd, which callers set. */
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
int poll(struct pollfd *fds, nfds_t n, int timeout)
{
	if (n == 1 && is_fake(fds[0].fd))
		return fake_poll(&fds[0], timeout);
	return real_poll(fds, n, timeout);
}
