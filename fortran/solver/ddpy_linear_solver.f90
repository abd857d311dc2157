!> Sparse direct solver: MUMPS behind integer handles of the core's handle table
!> (ddpy_handle_table), sequential or across MPI processes.
!>
!> A handle keeps one MUMPS instance with its sparsity structure, so the symbolic analysis
!> (job 1) is done once per structure and reused by every factorization (job 2) and solve
!> (job 3) of the Newton loop. MUMPS never prints: all its output units are switched off and
!> its error codes are returned as status values.
!>
!> Processes (docs/mpi.md): MUMPS's host-and-workers pattern (PAR = 1, the assembled matrix
!> centralized on the host). Rank 0 runs the driver and calls the solver_* procedures; each
!> of them that reaches MUMPS first broadcasts a command (what, handle, two values) to the
!> ranks > 0, which wait in solver_serve and make the same collective MUMPS call on their own
!> instance of the same handle. Rank 0 checks its arguments before it broadcasts, so every
!> command sent is a MUMPS call on every rank, and MUMPS's INFOG(1), the same on all ranks,
!> drives the retries alike. The sequential build runs the same code with one process (the
!> stub MPI of libmumps-seq: its broadcast does nothing).
!>
!> Precision: a solver created single factorizes and solves in single precision (MUMPS's
!> SMUMPS) on the double-precision matrix and right-hand sides it is given, and returns its
!> solutions in double precision. It keeps a double-precision instance beside it for the
!> structure, the controls and the pivot order, which the single one mirrors at each call:
!> half the factor memory and its traffic in the solves, for factors whose solutions
!> leave about eps_single times the condition number (docs/theory/linear-solver.md, "Single-
!> precision factors"): for preconditioning, as the forming loop's GMRES uses them.
!>
!> Never call MUMPS on two instances at the same time from threads of one process: MUMPS
!> keeps state outside its instances (its load module's arrays), so two factorizations
!> abort and two solves return wrong solutions (docs/theory/linear-solver.md). The
!> interface holds the GIL through every call (the .pyf releases it nowhere).
module ddpy_linear_solver
  use ddpy_kinds, only: wp
  use iso_fortran_env, only: int64
  use ddpy_build, only: parallel_mumps
  use ddpy_handle_table, only: table, max_handles, claim_handle, free_entry, entry_solver, &
                               handle_is => valid_handle, world, mpi_not_started, &
                               mpi_running, mpi_finished
  implicit none
  private
  public :: solver_create, solver_analyse, solver_factorize, solver_solve, &
            solver_destroy, solver_info, solver_set_control, solver_set_real_control, &
            solver_set_ordering, solver_world, solver_serve, solver_finish, &
            solver_analyse_elements, solver_precision

  include 'mpif.h'

  !> solver_create's precision.
  integer, parameter, public :: precision_double = 0, precision_single = 1

  !> The entries of solver_info's values (MUMPS's INFOG(1), INFOG(2), the ordering used, the
  !> factor entries and their estimate, the estimated memory of the factorization on the
  !> largest process and all, the memory allocated and used, the processes, the negative
  !> pivots, the workspace given to the last factorization: LWK_USER) and of its flops (the elimination's and its estimate).
  integer, parameter, public :: info_infog1 = 1, info_infog2 = 2, info_ordering = 3, &
                                info_factor_entries = 4, info_estimated_factor_entries = 5, &
                                info_estimated_memory_mb_max = 6, &
                                info_estimated_memory_mb_total = 7, info_memory_mb_max = 8, &
                                info_memory_mb_total = 9, info_memory_used_mb_max = 10, &
                                info_memory_used_mb_total = 11, info_processes = 12, &
                                info_negative_pivots = 13, info_workspace_given = 14, &
                                solver_info_values = 14
  integer, parameter, public :: flops_elimination = 1, flops_estimate = 2, solver_flops = 2

  !> MUMPS instances that may live at the same time (each holds its factors: a few of them
  !> fill a machine's memory), among the handles of the table.
  integer, parameter :: max_solvers = 16

  !> Status values besides MUMPS's own (negative INFOG(1) values are passed through).
  integer, parameter, public :: status_bad_handle = -1001, status_not_analysed = -1002, &
                                status_size_mismatch = -1003, status_no_free_handle = -1004, &
                                status_finished = -1005, status_not_host = -1006, &
                                status_not_positive_definite = -1007, &
                                status_bad_precision = -1008, &
                                status_single_too_coarse = -1009

  !> Commands rank 0 broadcasts to the ranks > 0: one integer message (command, handle,
  !> value, value, and a real value's bits or a third value in the last two: one type for
  !> every broadcast, which gfortran's argument checks ask of the implicit MPI interface).
  integer, parameter :: message_size = 6
  integer, parameter :: command_stop = 0, command_create = 1, command_analyse = 2, &
                        command_factorize = 3, command_solve = 4, command_destroy = 5, &
                        command_control = 6, command_real_control = 7


contains

  logical function valid_handle(handle)
    integer, intent(in) :: handle
    valid_handle = handle_is(handle, entry_solver)
  end function valid_handle

  !> Start MPI once (MPI_Init) and learn this process's rank and the number of processes.
  subroutine start_mpi()
    integer :: ierr
    if (world%state /= mpi_not_started) return
    call mpi_init(ierr)
    call mpi_comm_rank(mpi_comm_world, world%rank, ierr)
    call mpi_comm_size(mpi_comm_world, world%size, ierr)
    world%state = mpi_running
  end subroutine start_mpi

  !> This process's rank and the number of processes (MPI started here when it was not),
  !> parallel 1 for the parallel MUMPS build, 0 for the sequential one; status: 0, or
  !> status_finished after solver_finish.
  subroutine solver_world(rank, size, parallel, status)
    integer, intent(out) :: rank, size, parallel, status
    call start_mpi()
    rank = world%rank
    size = world%size
    parallel = merge(1, 0, parallel_mumps)
    status = 0
    if (world%state == mpi_finished) status = status_finished
  end subroutine solver_world

  !> Rank 0: send a command to the ranks > 0 (nothing to send with one process).
  subroutine send_command(command, handle, value1, value2, real_value, value3)
    integer, intent(in) :: command, handle, value1, value2
    real(wp), intent(in), optional :: real_value
    integer, intent(in), optional :: value3
    integer :: message(message_size), ierr
    if (world%size < 2) return
    message = 0
    message(1:4) = [command, handle, value1, value2]
    if (present(real_value)) message(5:6) = transfer(real_value, message(5:6))
    if (present(value3)) message(5) = value3
    call mpi_bcast(message, message_size, mpi_integer, 0, mpi_comm_world, ierr)
  end subroutine send_command

  !> Ranks > 0: run rank 0's solver commands until it sends stop (solver_finish), then end
  !> MPI. status: 0, or status_not_host on rank 0, which has nothing to serve.
  subroutine solver_serve(status)
    integer, intent(out) :: status
    integer :: message(message_size), ierr, handle, ignored
    call start_mpi()
    status = status_not_host
    if (world%rank == 0 .or. world%state /= mpi_running) return
    status = 0
    do
      call mpi_bcast(message, message_size, mpi_integer, 0, mpi_comm_world, ierr)
      handle = message(2)
      select case (message(1))
      case (command_create)
        call init_instance(handle, message(3), message(4), message(5), ignored)
      case (command_analyse)
        call drop_workspace(handle)
        call run_job(handle, 1, ignored)
        table(handle)%analysed = ignored >= 0
      case (command_factorize)
        call factorize_job(handle, ignored)
      case (command_solve)
        call run_job(handle, 3, ignored)
      case (command_destroy)
        call destroy_instance(handle, ignored)
      case (command_control)
        table(handle)%mumps%icntl(message(3)) = message(4)
      case (command_real_control)
        table(handle)%mumps%cntl(message(3)) = transfer(message(5:6), 0.0_wp)
      case default
        exit
      end select
    end do
    call end_mpi()
  end subroutine solver_serve

  !> Rank 0, at the end of the driver: free every instance (on all ranks), tell the ranks > 0
  !> to stop and end MPI. Later calls of the solver fail with status_finished.
  subroutine solver_finish(status)
    integer, intent(out) :: status
    integer :: handle, ignored
    status = 0
    if (world%state /= mpi_running) return
    if (world%rank /= 0) then
      status = status_not_host
      return
    end if
    do handle = 1, max_handles
      if (valid_handle(handle)) call solver_destroy(handle, ignored)
    end do
    call send_command(command_stop, 0, 0, 0)
    call end_mpi()
  end subroutine solver_finish

  subroutine end_mpi()
    integer :: ierr
    call mpi_finalize(ierr)
    world%state = mpi_finished
  end subroutine end_mpi

  !> Start a MUMPS instance. sym: 0 unsymmetric, 1 symmetric positive definite,
  !> 2 general symmetric. ordering: MUMPS ICNTL(7) (5 = METIS, 7 = automatic). precision:
  !> precision_double, or precision_single for factors and solves in single precision.
  subroutine solver_create(sym, ordering, precision, handle, status)
    integer, intent(in) :: sym, ordering, precision
    integer, intent(out) :: handle, status
    integer :: h
    handle = 0
    status = status_bad_precision
    if (precision /= precision_double .and. precision /= precision_single) return
    call start_mpi()
    status = status_finished
    if (world%state /= mpi_running) return
    status = status_not_host
    if (world%rank /= 0) return
    status = status_no_free_handle
    if (count([(valid_handle(h), h = 1, max_handles)]) >= max_solvers) return
    call claim_handle(entry_solver, handle)
    if (handle == 0) return
    call send_command(command_create, handle, sym, ordering, value3=precision)
    call init_instance(handle, sym, ordering, precision, status)
    if (status < 0) then
      call free_entry(handle)
      handle = 0
    end if
  end subroutine solver_create

  !> The collective MUMPS initialization (job -1) of one handle, on every rank (the ranks
  !> > 0 take the handle rank 0 chose); with precision_single, of its single instance too.
  subroutine init_instance(handle, sym, ordering, precision, status)
    integer, intent(in) :: handle, sym, ordering, precision
    integer, intent(out) :: status
    integer :: claimed
    claimed = handle
    call claim_handle(entry_solver, claimed)
    allocate(table(handle)%mumps)
    associate (id => table(handle)%mumps)
      id%comm = mpi_comm_world
      id%sym = sym
      id%par = 1
      id%job = -1
      call dmumps(id)
      status = id%infog(1)
      if (status < 0) return
      ! Silence MUMPS: the core never prints.
      id%icntl(1) = -1
      id%icntl(2) = -1
      id%icntl(3) = -1
      id%icntl(4) = 0
      id%icntl(7) = ordering
      ! Extra workspace: FE matrices with many equal pivots can outgrow the estimate.
      id%icntl(14) = 40
      nullify (id%irn, id%jcn, id%a, id%rhs, id%perm_in, id%eltptr, id%eltvar, id%wk_user)
    end associate
    table(handle)%analysed = .false.
    table(handle)%factorized = .false.
    if (precision /= precision_single) return
    allocate(table(handle)%single)
    associate (sp => table(handle)%single)
      sp%comm = mpi_comm_world
      sp%sym = sym
      sp%par = 1
      sp%job = -1
      call smumps(sp)
      status = sp%infog(1)
      nullify (sp%irn, sp%jcn, sp%a, sp%rhs, sp%perm_in, sp%eltptr, sp%eltvar, sp%wk_user)
    end associate
  end subroutine init_instance

  !> One collective MUMPS call (job) on a handle; status its INFOG(1), the same on all ranks.
  !> A single-precision handle's analysis, factorization and solve run on its single
  !> instance (run_single).
  subroutine run_job(handle, job, status)
    integer, intent(in) :: handle, job
    integer, intent(out) :: status
    if (allocated(table(handle)%single) .and. job >= 1) then
      call run_single(handle, job, status)
      return
    end if
    table(handle)%mumps%job = job
    call dmumps(table(handle)%mumps)
    status = table(handle)%mumps%infog(1)
  end subroutine run_job

  !> A job (1 analysis, 2 factorization, 3 solve) on the single instance: the controls of
  !> the double one first; at the analysis its structure and pivot order (pointers to its
  !> arrays: MUMPS reads the coordinates again when it factorizes) and arrays for the
  !> values and right-hand side; the values or the right-hand side converted in, the
  !> solution converted back into the double instance's rhs. Where an array is not
  !> associated (the ranks > 0 of an assembled, centralized matrix) nothing is converted.
  subroutine run_single(handle, job, status)
    integer, intent(in) :: handle, job
    integer, intent(out) :: status
    associate (sp => table(handle)%single, id => table(handle)%mumps)
      sp%icntl = id%icntl
      sp%cntl = real(id%cntl, kind(sp%cntl))
      select case (job)
      case (1)
        call release_single(handle)
        sp%n = id%n
        sp%nnz = id%nnz
        sp%nelt = id%nelt
        sp%irn => id%irn
        sp%jcn => id%jcn
        sp%eltptr => id%eltptr
        sp%eltvar => id%eltvar
        sp%perm_in => id%perm_in
        if (associated(id%a)) allocate(sp%a(size(id%a)), source=0.0)
        if (associated(id%rhs)) allocate(sp%rhs(size(id%rhs)), source=0.0)
      case (2)
        if (associated(id%a) .and. associated(sp%a)) sp%a = real(id%a, kind(sp%a))
      case (3)
        if (associated(id%rhs) .and. associated(sp%rhs)) sp%rhs = real(id%rhs, kind(sp%rhs))
      end select
      sp%job = job
      call smumps(sp)
      status = sp%infog(1)
      if (job == 3 .and. status >= 0 .and. associated(id%rhs) .and. associated(sp%rhs)) &
        id%rhs = real(sp%rhs, wp)
    end associate
  end subroutine run_single

  !> Drop the single instance's own arrays and its pointers to the double one's.
  subroutine release_single(handle)
    integer, intent(in) :: handle
    if (.not. allocated(table(handle)%single)) return
    associate (sp => table(handle)%single)
      if (associated(sp%a)) deallocate (sp%a)
      if (associated(sp%rhs)) deallocate (sp%rhs)
      nullify (sp%irn, sp%jcn, sp%eltptr, sp%eltvar, sp%perm_in, sp%a, sp%rhs)
    end associate
  end subroutine release_single

  !> Numerical factorization (job 2); on a workspace shortage (INFO -8, -9) the relaxation
  !> is raised and the factorization retried, on every rank alike.
  subroutine factorize_job(handle, status)
    integer, intent(in) :: handle
    integer, intent(out) :: status
    integer :: attempt
    if (allocated(table(handle)%single)) then
      ! MUMPS's own workspace: the single factors are half the double ones' pages
      do attempt = 1, 4
        call run_job(handle, 2, status)
        if (status /= -8 .and. status /= -9) exit
        table(handle)%mumps%icntl(14) = 2*table(handle)%mumps%icntl(14)
      end do
      table(handle)%factorized = status >= 0
      if (status >= 0 .and. table(handle)%single%sym == 1 .and. &
          table(handle)%single%infog(12) > 0) then
        status = status_not_positive_definite
        table(handle)%factorized = .false.
      end if
      return
    end if
    associate (id => table(handle)%mumps)
      ! The workspace of the last factorization kept for the next ones (MUMPS's user
      ! workspace, WK_USER): MUMPS frees its own at every factorization and allocates it
      ! again, 0.76 GB of fresh pages per LU on the paper blanks.
      if (id%lwk_user == 0 .and. table(handle)%workspace > 0) then
        ! LWK_USER counts entries, or millions of them when negative.
        if (table(handle)%workspace <= huge(id%lwk_user)) then
          id%lwk_user = int(table(handle)%workspace)
          allocate(id%wk_user(table(handle)%workspace))
        else
          id%lwk_user = -int((table(handle)%workspace + 999999_int64)/1000000_int64)
          allocate(id%wk_user(-1000000_int64*id%lwk_user))
        end if
      end if
      do attempt = 1, 4
        call run_job(handle, 2, status)
        if (status >= 0) then
          ! INFO(39): the entries of S MUMPS took, or millions of them when negative.
          if (id%lwk_user == 0) table(handle)%workspace = &
            merge(int(id%info(39), int64), -1000000_int64*id%info(39), id%info(39) >= 0)
          exit
        end if
        call drop_workspace(handle)
        if (status /= -8 .and. status /= -9) exit
        id%icntl(14) = 2*id%icntl(14)
      end do
    end associate
    table(handle)%factorized = status >= 0
    ! SYM = 1 factorizes LDL^T without pivoting, which completes on an indefinite matrix
    ! too: its negative pivots (INFOG(12), the same on every rank) tell that it is not
    ! positive definite, and its solutions would be an answer to the wrong question.
    if (status >= 0 .and. table(handle)%mumps%sym == 1 .and. table(handle)%mumps%infog(12) > 0) then
      status = status_not_positive_definite
      table(handle)%factorized = .false.
    end if
  end subroutine factorize_job

  !> status_size_mismatch where an ordering is to be given (ICNTL(7) = 1) and none of n
  !> entries was set, else 0.
  integer function ordering_status(handle, n) result(status)
    integer, intent(in) :: handle, n
    status = 0
    if (table(handle)%mumps%icntl(7) /= 1) return
    if (.not. associated(table(handle)%mumps%perm_in)) then
      status = status_size_mismatch
    else if (size(table(handle)%mumps%perm_in) /= n) then
      status = status_size_mismatch
    end if
  end function ordering_status

  !> Symbolic analysis of an n x n matrix given by its nz coordinates (1-based, duplicates
  !> are summed; for sym > 0 only one triangle is read).
  subroutine solver_analyse(handle, n, nz, irn, jcn, status)
    integer, intent(in) :: handle, n, nz
    integer, intent(in) :: irn(nz), jcn(nz)
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    status = ordering_status(handle, n)
    if (status /= 0) return
    call drop_workspace(handle)
    associate (id => table(handle)%mumps)
      call release_arrays(handle)
      allocate (id%irn(nz), id%jcn(nz), id%a(nz), id%rhs(n))
      id%icntl(5) = 0
      id%irn = irn
      id%jcn = jcn
      id%a = 0.0_wp
      id%n = n
      id%nnz = int(nz, kind=8)
    end associate
    call send_command(command_analyse, handle, 0, 0)
    call run_job(handle, 1, status)
    table(handle)%analysed = status >= 0
    table(handle)%factorized = .false.
  end subroutine solver_analyse

  !> Symbolic analysis of an n x n matrix given by its nelt elements (MUMPS's elemental
  !> input, ICNTL(5) = 1): element e couples the variables eltvar(eltptr(e):eltptr(e+1)-1)
  !> (1-based). For MUMPS's estimates of large structures (flops, factor entries, memory
  !> per process) at a fraction of the coordinates' memory: the handle is left unanalysed,
  !> so it cannot factorize; solver_info gives the estimates.
  subroutine solver_analyse_elements(handle, n, nelt, nvar, eltptr, eltvar, status)
    integer, intent(in) :: handle, n, nelt, nvar
    integer, intent(in) :: eltptr(nelt + 1), eltvar(nvar)
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    status = ordering_status(handle, n)
    if (status /= 0) return
    associate (id => table(handle)%mumps)
      call release_arrays(handle)
      allocate (id%eltptr(nelt + 1), id%eltvar(nvar))
      id%eltptr = eltptr
      id%eltvar = eltvar
      id%n = n
      id%nelt = nelt
      id%icntl(5) = 1
    end associate
    call send_command(command_analyse, handle, 0, 0)
    call run_job(handle, 1, status)
    call release_arrays(handle)
    table(handle)%analysed = .false.
    table(handle)%factorized = .false.
  end subroutine solver_analyse_elements

  !> Numerical factorization with new values on the analysed structure. On a workspace
  !> shortage (INFO -8, -9) the relaxation is raised and the factorization retried.
  subroutine solver_factorize(handle, nz, a, status)
    integer, intent(in) :: handle, nz
    real(wp), intent(in) :: a(nz)
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (.not. table(handle)%analysed) then
      status = status_not_analysed
      return
    end if
    if (int(nz, kind=8) /= table(handle)%mumps%nnz) then
      status = status_size_mismatch
      return
    end if
    table(handle)%mumps%a = a
    call send_command(command_factorize, handle, 0, 0)
    call factorize_job(handle, status)
  end subroutine solver_factorize

  !> Solve A x = rhs with the last factorization.
  subroutine solver_solve(handle, n, rhs, x, status)
    integer, intent(in) :: handle, n
    real(wp), intent(in) :: rhs(n)
    real(wp), intent(out) :: x(n)
    integer, intent(out) :: status
    x = 0.0_wp
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (.not. table(handle)%factorized) then
      status = status_not_analysed
      return
    end if
    if (n /= table(handle)%mumps%n) then
      status = status_size_mismatch
      return
    end if
    table(handle)%mumps%rhs = rhs
    call send_command(command_solve, handle, 0, 0)
    call run_job(handle, 3, status)
    if (status >= 0) x = table(handle)%mumps%rhs
  end subroutine solver_solve

  !> MUMPS statistics of the last call (rank 0, the host, holds them): values are INFOG(1),
  !> INFOG(2), the ordering used (INFOG(7)), entries in the factors (INFOG(29)), their
  !> estimate of the analysis (INFOG(3)), the estimated memory in MB of the factorization,
  !> largest process and all (INFOG(16), INFOG(17)), the memory the factorization allocated
  !> (INFOG(18), INFOG(19)) and used (INFOG(21), INFOG(22)), the number of processes and
  !> the negative pivots of the last factorization (INFOG(12), SYM = 1 or 2);
  !> factor entries may be negative when large (-value*1e6). flops: the elimination's
  !> (RINFOG(3)) and the analysis's estimate (RINFOG(1)).
  subroutine solver_info(handle, values, flops, status)
    integer, intent(in) :: handle
    integer, intent(out) :: values(solver_info_values)
    real(wp), intent(out) :: flops(solver_flops)
    integer, intent(out) :: status
    values = 0
    flops = 0.0_wp
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (allocated(table(handle)%single)) then
      associate (sp => table(handle)%single)
        call info_of(sp%infog, real(sp%rinfog, wp), sp%lwk_user, values, flops)
      end associate
    else
      associate (id => table(handle)%mumps)
        call info_of(id%infog, id%rinfog, id%lwk_user, values, flops)
      end associate
    end if
    status = 0
  end subroutine solver_info

  !> solver_info's values and flops from an instance's INFOG, RINFOG and LWK_USER (either
  !> precision's).
  subroutine info_of(infog, rinfog, lwk_user, values, flops)
    integer, intent(in) :: infog(:), lwk_user
    real(wp), intent(in) :: rinfog(:)
    integer, intent(out) :: values(solver_info_values)
    real(wp), intent(out) :: flops(solver_flops)
    values(info_infog1) = infog(1)
    values(info_infog2) = infog(2)
    values(info_ordering) = infog(7)
    values(info_factor_entries) = infog(29)
    values(info_estimated_factor_entries) = infog(3)
    values(info_estimated_memory_mb_max) = infog(16)
    values(info_estimated_memory_mb_total) = infog(17)
    values(info_memory_mb_max) = infog(18)
    values(info_memory_mb_total) = infog(19)
    values(info_memory_used_mb_max) = infog(21)
    values(info_memory_used_mb_total) = infog(22)
    values(info_processes) = world%size
    values(info_negative_pivots) = infog(12)
    values(info_workspace_given) = lwk_user
    flops(flops_elimination) = rinfog(3)
    flops(flops_estimate) = rinfog(1)
  end subroutine info_of

  !> Whether a handle's factors are single precision (precision_single) or not
  !> (precision_double); status_bad_handle for a handle that is not a solver's.
  subroutine solver_precision(handle, precision, status)
    integer, intent(in) :: handle
    integer, intent(out) :: precision, status
    precision = precision_double
    status = status_bad_handle
    if (.not. valid_handle(handle)) return
    status = 0
    if (allocated(table(handle)%single)) precision = precision_single
  end subroutine solver_precision

  !> Set MUMPS control ICNTL(index) = value (advanced use: ordering, refinement, memory).
  subroutine solver_set_control(handle, index, value, status)
    integer, intent(in) :: handle, index, value
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (index < 1 .or. index > size(table(handle)%mumps%icntl)) then
      status = status_size_mismatch
      return
    end if
    call send_command(command_control, handle, index, value)
    table(handle)%mumps%icntl(index) = value
    status = 0
  end subroutine solver_set_control

  !> Set MUMPS real control CNTL(index) = value (e.g. CNTL(7), the block low-rank
  !> compression tolerance).
  subroutine solver_set_real_control(handle, index, value, status)
    integer, intent(in) :: handle, index
    real(wp), intent(in) :: value
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (index < 1 .or. index > size(table(handle)%mumps%cntl)) then
      status = status_size_mismatch
      return
    end if
    call send_command(command_real_control, handle, index, 0, value)
    table(handle)%mumps%cntl(index) = value
    status = 0
  end subroutine solver_set_real_control

  !> Use the pivot order perm for the next analyses (MUMPS ICNTL(7) = 1): perm(i) is the
  !> position (1-based) of variable i in the pivot order. Only the host reads it.
  subroutine solver_set_ordering(handle, n, perm, status)
    integer, intent(in) :: handle, n, perm(n)
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    associate (id => table(handle)%mumps)
      if (associated(id%perm_in)) deallocate (id%perm_in)
      allocate (id%perm_in(n))
      id%perm_in = perm
      id%icntl(7) = 1
    end associate
    status = 0
  end subroutine solver_set_ordering

  !> Free a MUMPS instance and its arrays.
  subroutine solver_destroy(handle, status)
    integer, intent(in) :: handle
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    call send_command(command_destroy, handle, 0, 0)
    call destroy_instance(handle, status)
  end subroutine solver_destroy

  !> The collective MUMPS end (job -2) of one handle, on every rank.
  subroutine destroy_instance(handle, status)
    integer, intent(in) :: handle
    integer, intent(out) :: status
    integer :: single_status
    call release_arrays(handle)
    associate (id => table(handle)%mumps)
      if (associated(id%perm_in)) deallocate (id%perm_in)
    end associate
    single_status = 0
    if (allocated(table(handle)%single)) then
      table(handle)%single%job = -2
      call smumps(table(handle)%single)
      single_status = table(handle)%single%infog(1)
    end if
    call run_job(handle, -2, status)
    if (status >= 0) status = single_status
    call drop_workspace(handle)
    call free_entry(handle)
  end subroutine destroy_instance

  !> Take back the workspace given to MUMPS: its own is used from the next factorization.
  subroutine drop_workspace(handle)
    integer, intent(in) :: handle
    table(handle)%workspace = 0
    associate (id => table(handle)%mumps)
      if (associated(id%wk_user)) deallocate (id%wk_user)
      nullify (id%wk_user)
      id%lwk_user = 0
    end associate
  end subroutine drop_workspace

  subroutine release_arrays(handle)
    integer, intent(in) :: handle
    call release_single(handle)
    associate (id => table(handle)%mumps)
      if (associated(id%irn)) deallocate (id%irn)
      if (associated(id%jcn)) deallocate (id%jcn)
      if (associated(id%a)) deallocate (id%a)
      if (associated(id%rhs)) deallocate (id%rhs)
      if (associated(id%eltptr)) deallocate (id%eltptr)
      if (associated(id%eltvar)) deallocate (id%eltvar)
    end associate
  end subroutine release_arrays

end module ddpy_linear_solver
