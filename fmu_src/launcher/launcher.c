/* ChainDrive.so: the FMU's binary for every host (docs/fmu.md, "Hosts").
 *
 * pythonfmu's binary (shipped beside this one as BACKEND_FILE) runs the FMU's Python code but
 * does not link libpython: it only loads into a process that already has a Python. This
 * launcher exports the FMI 2.0 co-simulation functions and, at the first fmi2Instantiate:
 *
 * 1. if the process has an initialized Python (a Python host: fmpy, libcosimpy...), uses it;
 * 2. otherwise (a C/C++ host) loads the libpython recorded at build time (or the Python that
 *    CHAINDRIVE_PYTHON names: a python executable, a venv's too, or a libpython) with
 *    RTLD_GLOBAL and initializes it as that python executable would start: program name =
 *    the executable, so Python's own path calculation finds its home, a venv's pyvenv.cfg and
 *    site-packages, and site runs the .pth files (editable installs); PYTHONMALLOC=malloc if
 *    unset; no signal handlers of Python's (the host keeps its own);
 * 3. loads pythonfmu's binary and forwards every FMI call to it, through a thin instance of its
 *    own that mends three places where pythonfmu 0.7 departs from FMI 2.0 (section 4.2):
 *    - fmi2GetBooleanStatus(fmi2Terminated) is false: pythonfmu sets it on every discarded step,
 *      and a master that asks after fmi2Discard (Reference-FMUs' fmusim does) would then end the
 *      run early with status OK, where the FMU meant "retry this step" (section 4.2.3);
 *    - fmi2Fatal becomes fmi2Error, returned and logged: pythonfmu reports every Python
 *      exception as fatal ("irreparably corrupted for all FMU instances", section 2.1.3),
 *      though it concerns one instance (a bad parameter, a state that cannot be restored);
 *      some hosts abort the whole process on fmi2Fatal;
 *    - fmi2DoStep before fmi2ExitInitializationMode or after fmi2Terminate is refused with
 *      fmi2Error and a logged message (the state machine of section 4.2.4); pythonfmu steps.
 *    Its log line for an exception, whose text 0.7 never fetches ("unknown error"), is
 *    replaced by one naming the call and pointing at the error logged before it. And
 *    pythonfmu forwards no message without loggingOn, errors included: the backend is
 *    instantiated with logging on, and the launcher passes on warnings, discards and errors
 *    always, the rest as the host's loggingOn and fmi2SetDebugLogging categories say.
 *
 * Exit. pythonfmu 0.7's binary releases its interpreter guard twice at process exit (its static
 * std::shared_ptr's destructor, then its ELF destructor calling finalizePythonInterpreter on the
 * destroyed pointer; docs/fmu.md "What a host's process lives through"). The launcher registers
 * finalizePythonInterpreter with __cxa_atexit right after loading it, so it runs first and
 * leaves nothing to release twice. When the launcher initialized Python it does not finalize
 * it (module teardown with numpy, scipy and numba loaded is where embedded interpreters crash at
 * exit): at exit it runs Python's atexit functions and flushes sys.stdout and sys.stderr, then
 * leaves the interpreter to the operating system, as os._exit does.
 *
 * No Python header is needed: the few libpython functions used have plain C signatures that
 * are the same in every Python 3.
 *
 * Compiled by build_fmu.py: cc -shared -fPIC -O2 launcher.c -ldl -lpthread -Wl,-z,nodelete with
 * launcher_config.h (generated) defining RECORDED_PYTHON, RECORDED_LIBPYTHON, BACKEND_FILE and
 * FMU_NAME (for messages). Nothing in it is ChainDrive's: build_fmu.py --launch puts it in front
 * of any pythonfmu FMU's binary.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <wchar.h>

#include "fmi2/fmi2Functions.h"
#include "launcher_config.h"

#define OVERRIDE_VARIABLE "CHAINDRIVE_PYTHON"

extern char **environ;
extern int __cxa_atexit(void (*func)(void *), void *arg, void *dso_handle);

/* --- the backend: pythonfmu's binary ------------------------------------------------------ */

#define FMI2_FUNCTIONS(X) \
    X(fmi2SetDebugLogging) X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) \
    X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) \
    X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString) X(fmi2GetFMUstate) \
    X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative) \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)

#define DECLARE_POINTER(name) static name##TYPE *p_##name;
FMI2_FUNCTIONS(DECLARE_POINTER)

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static int loaded;                 /* backend resolved: instances can be made */
static char problem[4096];         /* why not, for the FMI logger */

/* --- libpython, when the launcher starts it ------------------------------------------------ */

typedef int (*IntVoidFn)(void);
static struct {
    IntVoidFn is_initialized;
    int (*gil_ensure)(void);       /* PyGILState_STATE is an int-sized enum */
    void (*gil_release)(int);
    int (*run_string)(const char *);
} py;

static const char EXIT_CODE[] =
    "import atexit, sys\n"
    "atexit._run_exitfuncs()\n"
    "for _f in (sys.stdout, sys.stderr):\n"
    "    try:\n"
    "        _f.flush()\n"
    "    except Exception:\n"
    "        pass\n";

static void python_at_exit(void *unused)
{
    (void)unused;
    if (py.is_initialized && py.is_initialized()) {
        int state = py.gil_ensure();
        py.run_string(EXIT_CODE);
        py.gil_release(state);
    }
}

static void set_problem(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(problem, sizeof problem, fmt, ap);
    va_end(ap);
}

/* The libpython of a python executable, as that python reports it (LIBDIR/INSTSONAME, or under
 * the multiarch directory as Debian installs it). Empty when it has none (a static build). */
static int ask_python_for_libpython(const char *python, char *out, size_t size)
{
    static const char code[] =
        "import os, sysconfig as s\n"
        "d, n, m = (s.get_config_var(k) or '' for k in ('LIBDIR', 'INSTSONAME', 'MULTIARCH'))\n"
        "c = [os.path.join(d, n), os.path.join(d, m, n)] if n else []\n"
        "print(next((p for p in c if os.path.isfile(p)), ''))\n";
    char *argv[] = {(char *)python, "-I", "-c", (char *)code, NULL};
    int fds[2];
    posix_spawn_file_actions_t actions;
    pid_t pid;
    size_t got = 0;
    ssize_t n;
    int status = -1;
    if (pipe(fds) != 0)
        return -1;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    if (posix_spawn(&pid, python, &actions, NULL, argv, environ) != 0) {
        posix_spawn_file_actions_destroy(&actions);
        close(fds[0]);
        close(fds[1]);
        return -1;
    }
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    while (got + 1 < size && (n = read(fds[0], out + got, size - 1 - got)) != 0) {
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            break;
        got += (size_t)n;
    }
    close(fds[0]);
    out[got] = '\0';
    out[strcspn(out, "\r\n")] = '\0';
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR)      /* the host ignores SIGCHLD: no status, judge by the output */
            return *out ? 0 : -1;
    }
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : -1;
}

static int is_library_name(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    return strncmp(base, "libpython", 9) == 0 || strstr(base, ".so") != NULL;
}

/* Start the Python of the build (or of CHAINDRIVE_PYTHON) in this process. 0: done. */
static int start_python(void)
{
    const char *override = getenv(OVERRIDE_VARIABLE);
    const char *python = RECORDED_PYTHON, *libpython = RECORDED_LIBPYTHON;
    char asked[4096], origin[4096 + 128];
    void *lib;
    IntVoidFn is_initialized;

    if (override && *override) {
        snprintf(origin, sizeof origin, "%s=%s", OVERRIDE_VARIABLE, override);
        if (is_library_name(override)) {
            python = NULL;
            libpython = override;
        } else {
            python = override;
            if (access(python, X_OK) != 0) {
                set_problem(FMU_NAME ": no Python to run in: %s is not an executable "
                            "file (%s); give a python executable (a venv's is fine) or a "
                            "libpython", python, origin);
                return -1;
            }
            if (ask_python_for_libpython(python, asked, sizeof asked) != 0 || !*asked) {
                set_problem(FMU_NAME ": no Python to run in: %s reports no shared "
                            "libpython (%s); use a Python built with --enable-shared, or "
                            "give its libpython", python, origin);
                return -1;
            }
            libpython = asked;
        }
    } else {
        snprintf(origin, sizeof origin, "recorded when the FMU was built with %s; set %s to "
                 "a python executable or a libpython to use another", RECORDED_PYTHON,
                 OVERRIDE_VARIABLE);
        if (!*libpython) {
            set_problem(FMU_NAME ": no Python to run in: the Python that built the FMU "
                        "(%s) has no shared libpython; set %s to a python executable or "
                        "libpython of a Python built with --enable-shared", RECORDED_PYTHON,
                        OVERRIDE_VARIABLE);
            return -1;
        }
        if (access(python, X_OK) != 0) {
            set_problem(FMU_NAME ": no Python to run in: looked for the python executable "
                        "%s and its libpython %s (%s): the executable does not exist", python,
                        libpython, origin);
            return -1;
        }
    }
    lib = dlopen(libpython, RTLD_NOW | RTLD_GLOBAL);
    if (!lib) {
        set_problem(FMU_NAME ": no Python to run in: looked for libpython %s (%s): %s",
                    libpython, origin, dlerror());
        return -1;
    }
    is_initialized = (IntVoidFn)dlsym(lib, "Py_IsInitialized");
    void (*initialize_ex)(int) = (void (*)(int))dlsym(lib, "Py_InitializeEx");
    void (*set_program_name)(const wchar_t *) =
        (void (*)(const wchar_t *))dlsym(lib, "Py_SetProgramName");
    wchar_t *(*decode)(const char *, size_t *) =
        (wchar_t * (*)(const char *, size_t *))dlsym(lib, "Py_DecodeLocale");
    void *(*save_thread)(void) = (void *(*)(void))dlsym(lib, "PyEval_SaveThread");
    py.gil_ensure = (int (*)(void))dlsym(lib, "PyGILState_Ensure");
    py.gil_release = (void (*)(int))dlsym(lib, "PyGILState_Release");
    py.run_string = (int (*)(const char *))dlsym(lib, "PyRun_SimpleString");
    if (!is_initialized || !initialize_ex || !set_program_name || !decode || !save_thread ||
        !py.gil_ensure || !py.gil_release || !py.run_string) {
        set_problem(FMU_NAME ": %s is not a usable libpython (%s): a function of "
                    "Python's C API is missing", libpython, origin);
        return -1;
    }
    if (is_initialized())    /* a Python linked into the host but not visible globally */
        return 0;
    setenv("PYTHONMALLOC", "malloc", 0);
    if (python) {            /* kept for the interpreter's lifetime, as Python requires */
        wchar_t *program = decode(python, NULL);
        if (program)
            set_program_name(program);
    }
    initialize_ex(0);
    save_thread();           /* release the GIL: pythonfmu takes it in every call */
    py.is_initialized = is_initialized;
    __cxa_atexit(python_at_exit, NULL, NULL);
    return 0;
}

/* Directory of this library (the FMU's binaries/<platform>/), with a trailing '/'. The address
 * asked about is a static function's: an exported one (fmi2Instantiate) could resolve to
 * another FMU's launcher when a host loads FMUs with RTLD_GLOBAL. */
static int own_directory(char *out, size_t size)
{
    Dl_info info;
    const char *slash;
    if (!dladdr((void *)&own_directory, &info) || !info.dli_fname)
        return -1;
    slash = strrchr(info.dli_fname, '/');
    if (!slash || (size_t)(slash - info.dli_fname + 2) > size)
        return -1;
    memcpy(out, info.dli_fname, (size_t)(slash - info.dli_fname + 1));
    out[slash - info.dli_fname + 1] = '\0';
    return 0;
}

static void load(void)
{
    char backend_path[4096];
    void *backend;
    void (*finalize)(void *);
    IntVoidFn host_python = (IntVoidFn)dlsym(RTLD_DEFAULT, "Py_IsInitialized");

    if (!(host_python && host_python()) && start_python() != 0) {
        fprintf(stderr, "%s\n", problem);
        return;
    }
    if (own_directory(backend_path, sizeof backend_path - strlen(BACKEND_FILE)) != 0) {
        set_problem(FMU_NAME ": cannot find the folder of its own binary (dladdr)");
        fprintf(stderr, "%s\n", problem);
        return;
    }
    strcat(backend_path, BACKEND_FILE);
    backend = dlopen(backend_path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!backend) {
        set_problem(FMU_NAME ": cannot load pythonfmu's binary %s: %s", backend_path,
                    dlerror());
        fprintf(stderr, "%s\n", problem);
        return;
    }
#define RESOLVE(name) p_##name = (name##TYPE *)dlsym(backend, #name);
    FMI2_FUNCTIONS(RESOLVE)
    if (!p_fmi2Instantiate) {
        set_problem(FMU_NAME ": %s exports no fmi2Instantiate", backend_path);
        fprintf(stderr, "%s\n", problem);
        return;
    }
    /* after the backend's static constructors registered pyState's destructor: runs first */
    finalize = (void (*)(void *))dlsym(backend, "finalizePythonInterpreter");
    if (finalize)
        __cxa_atexit(finalize, NULL, NULL);
    loaded = 1;
}

/* --- FMI 2.0 ------------------------------------------------------------------------------ */

/* Where an instance is in FMI 2.0's co-simulation state machine (section 4.2.4), as far as the
 * launcher saw it; after fmi2SetFMUstate the phase the state was taken in, UNKNOWN for a
 * deserialized one (the backend then checks for itself). */
enum phase { INSTANTIATED, INITIALIZING, STEPPING, TERMINATED, UNKNOWN };
static const char *const PHASE_NAMES[] = {"after fmi2Instantiate or fmi2Reset",
                                          "in initialization mode", "stepping",
                                          "after fmi2Terminate", "unknown"};

/* FMU states taken by fmi2GetFMUstate, each with the phase it was taken in, so that
 * fmi2SetFMUstate restores the phase too (a deserialized state's is UNKNOWN) */
#define SAVED_STATES 64

/* The fmi2Component the host holds: the backend's, the host's callbacks and the phase. */
typedef struct {
    fmi2Component backend;
    fmi2CallbackFunctions host;      /* the host's callbacks, as given */
    fmi2CallbackFunctions to_backend; /* the same with the logger below (the backend keeps a
                                         pointer to it: it lives as long as the instance) */
    char name[256];
    enum phase phase;
    fmi2Boolean logging_on;           /* the host's debug logging (fmi2Instantiate's loggingOn,
                                         then fmi2SetDebugLogging); the backend logs everything */
    size_t n_categories;              /* and the categories it asked for, none: all */
    char **categories;
    struct { fmi2FMUstate state; enum phase phase; } saved[SAVED_STATES];
} Instance;

static void remember_state(Instance *in, fmi2FMUstate state)
{
    int i, free_slot = -1;
    for (i = 0; i < SAVED_STATES; i++) {
        if (in->saved[i].state == state) {
            in->saved[i].phase = in->phase;
            return;
        }
        if (!in->saved[i].state && free_slot < 0)
            free_slot = i;
    }
    if (free_slot >= 0) {       /* more states than slots: the rest restore as UNKNOWN */
        in->saved[free_slot].state = state;
        in->saved[free_slot].phase = in->phase;
    }
}

static enum phase phase_of_state(Instance *in, fmi2FMUstate state, int forget)
{
    int i;
    for (i = 0; i < SAVED_STATES; i++)
        if (state && in->saved[i].state == state) {
            enum phase ph = in->saved[i].phase;
            if (forget)
                in->saved[i].state = NULL;
            return ph;
        }
    return UNKNOWN;
}

/* pythonfmu 0.7 logs a Python exception leaving the FMU's code as this prefix, "[call]
 * C function", a newline and the exception's repr, or "unknown error" where it fetched none (it
 * releases the instance's objects before fetching, and 0.7 as shipped fetches nothing) */
static const char PY_EXCEPTION[] = "Fatal py exception encountered: ";
static const char PY_UNKNOWN[] = "unknown error";

/* Whether the host hears a message: warnings, discards and errors always (they explain a
 * status, or a result outside the model's validity, as the Reference-FMUs log errors whatever
 * loggingOn says); the rest with debug logging on, in the categories the host asked for. */
static int heard(const Instance *in, fmi2Status status, fmi2String category)
{
    size_t i;
    if (status >= fmi2Warning)
        return 1;
    if (!in->logging_on)
        return 0;
    if (in->n_categories == 0)
        return 1;
    for (i = 0; i < in->n_categories; i++)
        if (category && strcmp(category, in->categories[i]) == 0)
            return 1;
    return 0;
}

/* The backend's logger calls, with fmi2Fatal logged as fmi2Error. pythonfmu passes the message
 * as the format and no arguments; it is forwarded the same way, but for its exception line
 * without the exception's text, which says which call failed and where the reason is. */
static void backend_logger(fmi2ComponentEnvironment env, fmi2String instanceName,
                           fmi2Status status, fmi2String category, fmi2String message, ...)
{
    Instance *in = (Instance *)env;
    fmi2Status mended = status == fmi2Fatal ? fmi2Error : status;
    fmi2String cat = status == fmi2Fatal && (category == NULL || !*category) ? "logStatusError"
                                                                             : category;
    const char *call, *end;
    if (!in->host.logger || !heard(in, mended, cat))
        return;
    if (message && strncmp(message, PY_EXCEPTION, sizeof PY_EXCEPTION - 1) == 0
        && (end = strchr(call = message + sizeof PY_EXCEPTION - 1, '\n')) != NULL
        && strcmp(end + 1, PY_UNKNOWN) == 0) {
        in->host.logger(in->host.componentEnvironment, instanceName, mended, cat,
                        FMU_NAME ": its Python code raised an exception in %.*s; "
                        "pythonfmu 0.7 passes on no text of it: the error logged before this one, "
                        "if any, says why", (int)(end - call), call);
        return;
    }
    in->host.logger(in->host.componentEnvironment, instanceName, mended, cat, message);
}

static void log_error(Instance *in, const char *fmt, ...)
{
    char text[1024];
    va_list ap;
    if (!in->host.logger)
        return;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    in->host.logger(in->host.componentEnvironment, in->name, fmi2Error, "logStatusError", "%s",
                    text);
}

static fmi2Status mend(fmi2Status s) { return s == fmi2Fatal ? fmi2Error : s; }

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    Instance *in;
    pthread_once(&load_once, load);
    if (!loaded) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "%s", problem);
        return NULL;
    }
    if (!functions) /* FMI 2.0 requires the callbacks; the backend would crash without them */
        return NULL;
    in = (Instance *)calloc(1, sizeof *in);
    if (!in) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "%s", FMU_NAME ": out of memory");
        return NULL;
    }
    in->host = *functions;
    in->to_backend = *functions;
    in->to_backend.logger = backend_logger;
    in->to_backend.componentEnvironment = in;
    snprintf(in->name, sizeof in->name, "%s", instanceName ? instanceName : "");
    in->phase = INSTANTIATED;
    in->logging_on = loggingOn;
    /* pythonfmu forwards nothing, errors included, without loggingOn: it logs everything to
     * the launcher, which passes on what the host asked for (heard) */
    in->backend = p_fmi2Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                    &in->to_backend, visible, fmi2True);
    if (!in->backend) {
        free(in);
        return NULL;
    }
    return in;
}

/* every other call: to the backend (no instance can exist without it), fmi2Fatal as fmi2Error */
#define IN ((Instance *)c)
#define CALL(name, c, ...) \
    return p_##name && (c) ? mend(p_##name(IN->backend, ##__VA_ARGS__)) : fmi2Error
/* the same, moving to phase `next` when the call succeeds */
#define CALL_TO(next, name, c, ...) \
    do { \
        fmi2Status s_; \
        if (!p_##name || !(c)) \
            return fmi2Error; \
        s_ = mend(p_##name(IN->backend, ##__VA_ARGS__)); \
        if (s_ == fmi2OK || s_ == fmi2Warning) \
            IN->phase = (next); \
        return s_; \
    } while (0)

static void forget_categories(Instance *in)
{
    size_t i;
    for (i = 0; i < in->n_categories; i++)
        free(in->categories[i]);
    free(in->categories);
    in->categories = NULL;
    in->n_categories = 0;
}

/* kept here, not passed on: the backend keeps logging everything to backend_logger */
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                               const fmi2String categories[])
{
    size_t i;
    if (!c)
        return fmi2Error;
    if (n > 0 && !categories) {
        log_error(IN, "fmi2SetDebugLogging: nCategories = %zu but categories is NULL", n);
        return fmi2Error;
    }
    forget_categories(IN);
    IN->logging_on = on;
    if (n == 0)
        return fmi2OK;
    IN->categories = (char **)calloc(n, sizeof *IN->categories);
    for (i = 0; IN->categories && i < n; i++)
        if (!categories[i] || !(IN->categories[IN->n_categories++] = strdup(categories[i])))
            break;
    if (!IN->categories || i < n) {
        forget_categories(IN);
        log_error(IN, "fmi2SetDebugLogging: category %zu is NULL or out of memory; debug logging "
                  "is %s for all categories", i, on ? "on" : "off");
        return fmi2Error;
    }
    return fmi2OK;
}

void fmi2FreeInstance(fmi2Component c)
{
    if (!c)
        return;
    if (p_fmi2FreeInstance)
        p_fmi2FreeInstance(IN->backend);
    forget_categories(IN);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{ CALL(fmi2SetupExperiment, c, toleranceDefined, tolerance, startTime, stopTimeDefined,
       stopTime); }

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{ CALL_TO(INITIALIZING, fmi2EnterInitializationMode, c); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{ CALL_TO(STEPPING, fmi2ExitInitializationMode, c); }
fmi2Status fmi2Terminate(fmi2Component c) { CALL_TO(TERMINATED, fmi2Terminate, c); }
fmi2Status fmi2Reset(fmi2Component c) { CALL_TO(INSTANTIATED, fmi2Reset, c); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[])
{ CALL(fmi2GetReal, c, vr, n, value); }
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[])
{ CALL(fmi2GetInteger, c, vr, n, value); }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[])
{ CALL(fmi2GetBoolean, c, vr, n, value); }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[])
{ CALL(fmi2GetString, c, vr, n, value); }
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[])
{ CALL(fmi2SetReal, c, vr, n, value); }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer value[])
{ CALL(fmi2SetInteger, c, vr, n, value); }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[])
{ CALL(fmi2SetBoolean, c, vr, n, value); }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[])
{ CALL(fmi2SetString, c, vr, n, value); }

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    fmi2Status s;
    if (!p_fmi2GetFMUstate || !c || !state)
        return fmi2Error;
    s = mend(p_fmi2GetFMUstate(IN->backend, state));
    if (s == fmi2OK || s == fmi2Warning)
        remember_state(IN, *state);
    return s;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{ CALL_TO(phase_of_state(IN, state, 0), fmi2SetFMUstate, c, state); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    if (c && state)
        phase_of_state(IN, *state, 1);
    CALL(fmi2FreeFMUstate, c, state);
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
{ CALL(fmi2SerializedFMUstateSize, c, state, size); }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size)
{ CALL(fmi2SerializeFMUstate, c, state, bytes, size); }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state)
{ CALL(fmi2DeSerializeFMUstate, c, bytes, size, state); }

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[],
                                        size_t nUnknown, const fmi2ValueReference vKnown[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{ CALL(fmi2GetDirectionalDerivative, c, vUnknown, nUnknown, vKnown, nKnown, dvKnown,
       dvUnknown); }

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[])
{ CALL(fmi2SetRealInputDerivatives, c, vr, n, order, value); }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[])
{ CALL(fmi2GetRealOutputDerivatives, c, vr, n, order, value); }
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    if (c && IN->phase != STEPPING && IN->phase != UNKNOWN) {
        log_error(IN, "fmi2DoStep called %s; FMI 2.0 allows it only between "
                  "fmi2ExitInitializationMode and fmi2Terminate", PHASE_NAMES[IN->phase]);
        return fmi2Error;
    }
    CALL(fmi2DoStep, c, t, h, noSetPrior);
}
fmi2Status fmi2CancelStep(fmi2Component c) { CALL(fmi2CancelStep, c); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{ CALL(fmi2GetStatus, c, s, value); }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{ CALL(fmi2GetRealStatus, c, s, value); }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{ CALL(fmi2GetIntegerStatus, c, s, value); }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    if (c && s == fmi2Terminated) {   /* the FMU never asks to end: a discarded step may be
                                         retried (see the top of this file) */
        if (!value)
            return fmi2Error;
        *value = fmi2False;
        return fmi2OK;
    }
    CALL(fmi2GetBooleanStatus, c, s, value);
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{ CALL(fmi2GetStringStatus, c, s, value); }
