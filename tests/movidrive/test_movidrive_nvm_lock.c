/* file_nvm's lock (file_nvm.h): one process at a time on an EEPROM file. A second process is
 * refused with the holder's pid, the file untouched, until the holder closes or dies; the same
 * struct opened again keeps working (its old lock goes first); the lock is on PATH.lock, so it
 * outlives the rename of every write. */
#define _POSIX_C_SOURCE 200809L // NOLINT(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "sim_hal/file_nvm.h"

static char dir[512];
static char path[600];
static file_nvm_t nvm;

/* In a child: file_nvm_open's result (0..2 for 1, 0, -1), and its text into pipe fd. */
static int open_elsewhere(char *text, size_t n)
{
    int p[2];
    if (pipe(p) != 0) {
        return -1;
    }
    pid_t pid = fork();
    if (pid == 0) {
        static file_nvm_t other;
        char e[1000];
        int rc = file_nvm_open(&other, path, 64, e, sizeof e);
        const uint8_t one[1] = {1};
        hal_nvm_t h = file_nvm_hal(&other);
        int wrc = h.ops->write(h.ctx, 0, one, 1); /* refused when not ours */
        if (write(p[1], e, strlen(e) + 1u) < 0) {
            _exit(9);
        }
        _exit(rc == 0 && wrc == 0 ? 0 : rc < 0 && wrc < 0 ? 2 : 3);
    }
    close(p[1]);
    ssize_t got = read(p[0], text, n - 1u);
    text[got > 0 ? got : 0] = '\0';
    close(p[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static void test_second_process_refused(void)
{
    snprintf(path, sizeof path, "%s/lock.ee", dir);
    char e[1000];
    char want[2 * sizeof path + 64]; /* the path twice and the text around it */
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    hal_nvm_t h = file_nvm_hal(&nvm);
    const uint8_t seven[1] = {7};
    CHECK_EQ(h.ops->write(h.ctx, 0, seven, 1), 0); /* renamed over PATH: the lock stays */
    struct stat before;
    CHECK_EQ(stat(path, &before), 0);
    CHECK_EQ(open_elsewhere(e, sizeof e), 2);
    snprintf(want, sizeof want, "%s: in use by another process (pid %ld, lock %s.lock)", path,
             (long)getpid(), path);
    CHECK_STR(e, want);
    char checked[1000];
    CHECK_EQ(file_nvm_check_path(path, checked, sizeof checked), FILE_NVM_UNUSABLE);
    CHECK_STR(checked, want);
    struct stat after;
    CHECK_EQ(stat(path, &after), 0);
    CHECK(after.st_ino == before.st_ino && after.st_mtime == before.st_mtime);
    /* the same struct again: its own old lock does not stand in the way */
    CHECK_EQ(file_nvm_open(&nvm, path, 64, e, sizeof e), 0);
    uint8_t b[1];
    CHECK_EQ(h.ops->read(h.ctx, 0, b, 1), 0);
    CHECK_EQ(b[0], 7);
    /* another struct in this process is another user too */
    static file_nvm_t twin;
    CHECK_EQ(file_nvm_open(&twin, path, 64, e, sizeof e), -1);
    CHECK_EQ(twin.loaded, FILE_NVM_IMAGE_IN_USE);
    file_nvm_close(&nvm);
    CHECK_EQ(file_nvm_check_path(path, checked, sizeof checked), 0);
    CHECK_EQ(open_elsewhere(e, sizeof e), 0); /* closed: the next one may */
    CHECK_STR(e, "");
}

static void test_directories(void)
{
    char e[1000];
    char want[sizeof path + sizeof dir + 64];
    snprintf(path, sizeof path, "%s/nodir/x.ee", dir);
    CHECK_EQ(file_nvm_check_path(path, e, sizeof e), FILE_NVM_UNUSABLE);
    snprintf(want, sizeof want, "%s: the directory %s/nodir does not exist", path, dir);
    CHECK_STR(e, want);
    CHECK_EQ(file_nvm_check_path("fresh.ee", e, sizeof e), 0); /* the current directory */
}

int main(int argc, char **argv)
{
    snprintf(dir, sizeof dir, "%s/nvm_lock_XXXXXX", argc > 1 ? argv[1] : "/tmp");
    if (mkdtemp(dir) == NULL) {
        perror(dir);
        return 1;
    }
    RUN_TEST(test_second_process_refused);
    RUN_TEST(test_directories);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) {
        fprintf(stderr, "could not remove %s\n", dir);
    }
    return check_report();
}
