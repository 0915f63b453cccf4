/* batch_key.c — the cache key of a batch job (batch.h): SHA-256 (nettle)
 * over a plain-text description of everything that decides the job's bytes.
 *
 *   meso-batch-key 1
 *   mesobake 0.1.0 format 1.0 cache 1 arch x86_64
 *   build 64:9c1e...               (build_fingerprint: the binaries that bake)
 *   command shell
 *   input 7:bunny.obj
 *   arg 15:--thickness-rel
 *   arg 4:0.05
 *   file 7:bunny.obj 3f5c...      (SHA-256 of the contents)
 *
 * Every string is length-prefixed, so no two job descriptions run together
 * into the same text. Paths enter as written (the file records the input's
 * base name, so the name is part of the output), never as absolute paths:
 * two machines with the project at different places share keys.
 *
 * Why SHA-256 and nettle: a key shared by machines over a file system must
 * not collide by accident across millions of entries (a 64-bit hash would
 * be a birthday risk at farm scale), and Debian's nettle is small, well-kept
 * and already beside GnuTLS on most systems.
 */
#include "batch.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <nettle/sha2.h>

#include "cli_util.h"

/* The machine the bytes were computed on: floating point is deterministic
 * for one build on one architecture (rule 7), but e.g. aarch64 compilers
 * contract a*b+c into fused multiply-adds that round differently, so a
 * cache shared by x86-64 and arm64 machines keeps their bakes apart. */
#if defined(__x86_64__)
#define BATCH_ARCH "x86_64"
#elif defined(__aarch64__)
#define BATCH_ARCH "aarch64"
#elif defined(__i386__)
#define BATCH_ARCH "i386"
#else
#define BATCH_ARCH "other"
#endif

static void put_str(struct sha256_ctx* h, const char* tag, const char* s)
{
    char head[64];
    int n = snprintf(head, sizeof head, "%s %zu:", tag, strlen(s));
    sha256_update(h, (size_t)n, (const uint8_t*)head);
    sha256_update(h, strlen(s), (const uint8_t*)s);
    sha256_update(h, 1, (const uint8_t*)"\n");
}

static void hex(const uint8_t* d, size_t n, char* out)
{
    static const char digits[] = "0123456789abcdef";
    for (size_t i = 0; i < n; ++i) {
        out[2 * i] = digits[d[i] >> 4];
        out[2 * i + 1] = digits[d[i] & 15];
    }
    out[2 * n] = 0;
}

/* SHA-256 of a file's contents, as hex; 0 when it cannot be read. */
static int hash_file(int dirfd, const char* path, char out[65])
{
    int fd = openat(dirfd, path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    struct sha256_ctx h;
    sha256_init(&h);
    static uint8_t buf[1 << 16];
    ssize_t n;
    while ((n = read(fd, buf, sizeof buf)) > 0)
        sha256_update(&h, (size_t)n, buf);
    close(fd);
    if (n < 0)
        return 0;
    uint8_t d[SHA256_DIGEST_SIZE];
    sha256_digest(&h, sizeof d, d);
    hex(d, sizeof d, out);
    return 1;
}

static int is_regular(int dirfd, const char* path)
{
    struct stat st;
    return path[0] && fstatat(dirfd, path, &st, 0) == 0 && S_ISREG(st.st_mode);
}

static int put_file(struct sha256_ctx* h, int dirfd, const char* path);

static int hex_digit(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

/* A .gltf names more files than its own: buffers[].uri and images[].uri
 * that are not data: URIs, relative to its folder (percent-escapes
 * decoded, as tinygltf does). Each is hashed like an argument's file, so
 * editing scene.bin changes the key; one that cannot be read goes in as
 * "missing" (the bake itself reports it). A .gltf that does not parse adds
 * nothing (the bake refuses it). Files above 256 MiB are not parsed here:
 * their own hash already keys them, and glTF JSON that large is not a
 * content pipeline's. */
static int put_gltf_uris(struct sha256_ctx* h, int dirfd, const char* path)
{
    int fd = openat(dirfd, path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || st.st_size > (256 << 20)) {
        if (fd >= 0)
            close(fd);
        return 1;
    }
    char* text = malloc((size_t)st.st_size + 1);
    ssize_t got = text ? read(fd, text, (size_t)st.st_size) : -1;
    close(fd);
    if (got != (ssize_t)st.st_size) {
        free(text);
        return text ? 1 : 0;
    }
    text[got] = 0;
    cJSON* doc = cJSON_Parse(text);
    free(text);
    const char* slash = strrchr(path, '/');
    const size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    int ok = 1;
    static const char* const arrays[2] = {"buffers", "images"};
    for (int k = 0; k < 2 && ok; ++k) {
        const cJSON* item;
        cJSON_ArrayForEach(item, cJSON_GetObjectItemCaseSensitive(doc, arrays[k]))
        {
            const cJSON* uri = cJSON_GetObjectItemCaseSensitive(item, "uri");
            if (!cJSON_IsString(uri) || !strncmp(uri->valuestring, "data:", 5))
                continue;
            const size_t n = strlen(uri->valuestring);
            char* file = malloc(dir_len + n + 1);
            if (!file) {
                ok = 0;
                break;
            }
            memcpy(file, path, dir_len);
            size_t o = dir_len;
            const char* u = uri->valuestring;
            for (size_t i = 0; i < n; ++i) { /* %XX -> byte */
                const int hi = i + 2 < n && u[i] == '%' ? hex_digit(u[i + 1]) : -1;
                const int lo = hi >= 0 ? hex_digit(u[i + 2]) : -1;
                if (lo >= 0) {
                    file[o++] = (char)(hi * 16 + lo);
                    i += 2;
                } else {
                    file[o++] = u[i];
                }
            }
            file[o] = 0;
            if (!is_regular(dirfd, file) || !put_file(h, dirfd, file)) {
                put_str(h, "file", file);
                put_str(h, "sha256", "missing");
            }
            free(file);
        }
    }
    cJSON_Delete(doc);
    return ok;
}

/* `path` as a file the job reads: its name and the hash of its contents
 * (and of the files a .gltf names). */
static int put_file(struct sha256_ctx* h, int dirfd, const char* path)
{
    char digest[65];
    if (!hash_file(dirfd, path, digest))
        return 0;
    put_str(h, "file", path);
    put_str(h, "sha256", digest);
    const size_t n = strlen(path);
    if (n > 5 && !strcasecmp(path + n - 5, ".gltf"))
        return put_gltf_uris(h, dirfd, path);
    return 1;
}

/* An argument, and each ':'-separated part of it, that names a regular
 * file (e.g. --texture height:bricks.png, volume:rock.vdb:density). */
static int put_arg_files(struct sha256_ctx* h, int dirfd, const char* arg)
{
    if (is_regular(dirfd, arg))
        return put_file(h, dirfd, arg);
    if (!strchr(arg, ':'))
        return 1;
    char* copy = strdup(arg);
    if (!copy)
        return 0;
    int ok = 1;
    char* save = NULL;
    for (char* part = strtok_r(copy, ":", &save); part && ok; part = strtok_r(NULL, ":", &save))
        if (is_regular(dirfd, part))
            ok = put_file(h, dirfd, part);
    free(copy);
    return ok;
}

/* The options of each command that take no value (cmd_<command>.c). Every
 * other word starting with '-' takes the next word as its value, which is
 * hashed as it is even when it looks like -v or --max-memory. A flag
 * missing here only makes the key stricter (its next word is kept), never
 * looser. */
static int is_flag(const char* command, const char* s)
{
    static const char* const common[] = {"-v", "--verbose", "-h", "--help"};
    static const char* const mesh[] = {"--draco"};
    static const char* const shell[] = {"--repair", "--no-repair", "--allow-defects"};
    static const char* const frusta[] = {"--no-fit", "--keep-cap-intersections"};
    for (size_t k = 0; k < sizeof common / sizeof common[0]; ++k)
        if (!strcmp(s, common[k]))
            return 1;
    const char* const* list = !strcmp(command, "mesh")     ? mesh
                              : !strcmp(command, "shell")  ? shell
                              : !strcmp(command, "frusta") ? frusta
                                                           : NULL;
    const size_t n = list == mesh ? 1 : list == shell ? 3 : list ? 2 : 0;
    for (size_t k = 0; k < n; ++k)
        if (!strcmp(s, list[k]))
            return 1;
    return 0;
}

static int by_digest(const void* a, const void* b)
{
    return memcmp(a, b, 65);
}

/* The build: SHA-256 over the contents of every file this process has
 * mapped executable (mesobake, libmeso_bake, the adapters' libraries:
 * OpenVDB, Draco, OpenMesh, libpng, the C and C++ runtimes), sorted so the
 * address layout does not matter. Any rebuild or library update that could
 * change a bake's bytes changes the key; the same binaries on another
 * machine (a farm deploying one build) give the same key. Computed once. */
static const char* build_fingerprint(void)
{
    static char out[65];
    if (out[0])
        return out;
    snprintf(out, sizeof out, "unknown");
    FILE* maps = fopen("/proc/self/maps", "r");
    if (!maps)
        return out;
    char (*digests)[65] = NULL, line[4608], last[4096] = "";
    size_t n = 0;
    while (fgets(line, sizeof line, maps)) {
        char perms[8] = "", *path = strchr(line, '/');
        if (sscanf(line, "%*s %7s", perms) != 1 || perms[2] != 'x' || !path)
            continue;
        path[strcspn(path, "\n")] = 0;
        if (!strcmp(path, last) || strlen(path) >= sizeof last)
            continue;
        snprintf(last, sizeof last, "%s", path);
        char(*grown)[65] = realloc(digests, (n + 1) * sizeof *digests);
        if (!grown)
            break;
        digests = grown;
        if (hash_file(AT_FDCWD, path, digests[n]))
            ++n;
    }
    fclose(maps);
    qsort(digests, n, sizeof *digests, by_digest);
    struct sha256_ctx h;
    sha256_init(&h);
    for (size_t i = 0; i < n; ++i)
        sha256_update(&h, 64, (const uint8_t*)digests[i]);
    free(digests);
    uint8_t d[SHA256_DIGEST_SIZE];
    sha256_digest(&h, sizeof d, d);
    hex(d, sizeof d, out);
    return out;
}

meso_result batch_job_key(const batch_manifest* m, batch_job* job, meso_error* err)
{
    job->key[0] = 0;
    int dirfd = open(m->dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dirfd < 0)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot open: %s", m->dir, strerror(errno));
    struct sha256_ctx h;
    sha256_init(&h);
    char line[128];
    int n = snprintf(line, sizeof line, "meso-batch-key 1\nmesobake %s format %d.%d cache %d arch %s\n",
                     MESO_VERSION_STRING, MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR, MESO_BATCH_CACHE_VERSION, BATCH_ARCH);
    sha256_update(&h, (size_t)n, (const uint8_t*)line);
    put_str(&h, "build", build_fingerprint());
    put_str(&h, "command", job->command);
    put_str(&h, "input", job->input);
    for (size_t a = 0; a < job->arg_count; ++a) {
        const char* s = job->args[a];
        const int flag = is_flag(job->command, s);
        if (!strcmp(s, "-v") || !strcmp(s, "--verbose"))
            continue; /* what is printed, not what is baked */
        if (!strcmp(s, "--max-memory") && a + 1 < job->arg_count) {
            ++a; /* a limit refuses a bake or not; it never changes its bytes */
            continue;
        }
        put_str(&h, "arg", s);
        if (!flag && s[0] == '-' && a + 1 < job->arg_count)
            put_str(&h, "arg", job->args[++a]); /* its value, whatever it looks like */
    }
    int ok = put_file(&h, dirfd, job->input);
    for (size_t a = 0; a < job->arg_count && ok; ++a)
        ok = put_arg_files(&h, dirfd, job->args[a]);
    close(dirfd);
    if (!ok)
        return MESO_OK; /* no key: the bake runs (uncached) and reports the missing file itself */
    uint8_t d[SHA256_DIGEST_SIZE];
    sha256_digest(&h, sizeof d, d);
    hex(d, sizeof d, job->key);
    return MESO_OK;
}
