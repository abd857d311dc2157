!> Sparse direct solver: sequential MUMPS behind integer handles.
!>
!> A handle keeps one MUMPS instance with its sparsity structure, so the symbolic analysis
!> (job 1) is done once per structure and reused by every factorization (job 2) and solve
!> (job 3) of the Newton loop. MUMPS never prints: all its output units are switched off and
!> its error codes are returned as status values.
module ddpy_linear_solver
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: max_solvers, solver_create, solver_analyse, solver_factorize, solver_solve, &
            solver_destroy, solver_info, solver_set_control, solver_set_real_control, &
            solver_set_ordering

  include 'dmumps_struc.h'

  !> Number of solver instances that may live at the same time.
  integer, parameter :: max_solvers = 16

  !> Status values besides MUMPS's own (negative INFOG(1) values are passed through).
  integer, parameter, public :: status_bad_handle = -1001, status_not_analysed = -1002, &
                                status_size_mismatch = -1003, status_no_free_handle = -1004

  type(dmumps_struc), target, save :: instance(max_solvers)
  logical, save :: in_use(max_solvers) = .false.
  logical, save :: analysed(max_solvers) = .false.
  logical, save :: factorized(max_solvers) = .false.

contains

  logical function valid_handle(handle)
    integer, intent(in) :: handle
    valid_handle = .false.
    if (handle < 1 .or. handle > max_solvers) return
    valid_handle = in_use(handle)
  end function valid_handle

  !> Start a MUMPS instance. sym: 0 unsymmetric, 1 symmetric positive definite,
  !> 2 general symmetric. ordering: MUMPS ICNTL(7) (5 = METIS, 7 = automatic).
  subroutine solver_create(sym, ordering, handle, status)
    integer, intent(in) :: sym, ordering
    integer, intent(out) :: handle, status
    include 'mpif.h'
    integer :: h, ierr
    logical, save :: mpi_started = .false.
    handle = 0
    status = status_no_free_handle
    do h = 1, max_solvers
      if (.not. in_use(h)) then
        handle = h
        exit
      end if
    end do
    if (handle == 0) return
    if (.not. mpi_started) then
      call mpi_init(ierr)
      mpi_started = .true.
    end if
    associate (id => instance(handle))
      id%comm = mpi_comm_world
      id%sym = sym
      id%par = 1
      id%job = -1
      call dmumps(id)
      status = id%infog(1)
      if (status < 0) then
        handle = 0
        return
      end if
      ! Silence MUMPS: the core never prints.
      id%icntl(1) = -1
      id%icntl(2) = -1
      id%icntl(3) = -1
      id%icntl(4) = 0
      id%icntl(7) = ordering
      ! Extra workspace: FE matrices with many equal pivots can outgrow the estimate.
      id%icntl(14) = 40
      nullify (id%irn, id%jcn, id%a, id%rhs, id%perm_in)
    end associate
    in_use(handle) = .true.
    analysed(handle) = .false.
    factorized(handle) = .false.
  end subroutine solver_create

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
    associate (id => instance(handle))
      if (id%icntl(7) == 1) then
        if (.not. associated(id%perm_in)) then
          status = status_size_mismatch
          return
        else if (size(id%perm_in) /= n) then
          status = status_size_mismatch
          return
        end if
      end if
      call release_arrays(handle)
      allocate (id%irn(nz), id%jcn(nz), id%a(nz), id%rhs(n))
      id%irn = irn
      id%jcn = jcn
      id%a = 0.0_wp
      id%n = n
      id%nnz = int(nz, kind=8)
      id%job = 1
      call dmumps(id)
      status = id%infog(1)
    end associate
    analysed(handle) = status >= 0
    factorized(handle) = .false.
  end subroutine solver_analyse

  !> Numerical factorization with new values on the analysed structure. On a workspace
  !> shortage (INFO -8, -9) the relaxation is raised and the factorization retried.
  subroutine solver_factorize(handle, nz, a, status)
    integer, intent(in) :: handle, nz
    real(wp), intent(in) :: a(nz)
    integer, intent(out) :: status
    integer :: attempt
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (.not. analysed(handle)) then
      status = status_not_analysed
      return
    end if
    associate (id => instance(handle))
      if (int(nz, kind=8) /= id%nnz) then
        status = status_size_mismatch
        return
      end if
      id%a = a
      do attempt = 1, 4
        id%job = 2
        call dmumps(id)
        status = id%infog(1)
        if (status /= -8 .and. status /= -9) exit
        id%icntl(14) = 2*id%icntl(14)
      end do
    end associate
    factorized(handle) = status >= 0
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
    if (.not. factorized(handle)) then
      status = status_not_analysed
      return
    end if
    associate (id => instance(handle))
      if (n /= id%n) then
        status = status_size_mismatch
        return
      end if
      id%rhs = rhs
      id%job = 3
      call dmumps(id)
      status = id%infog(1)
      if (status >= 0) x = id%rhs
    end associate
  end subroutine solver_solve

  !> MUMPS statistics of the last call: INFOG(1), INFOG(2), ordering used (INFOG(7)),
  !> entries in the factors (INFOG(29), may be negative when large: -value*1e6), and
  !> estimated flops of the elimination (RINFOG(3)).
  subroutine solver_info(handle, values, flops, status)
    integer, intent(in) :: handle
    integer, intent(out) :: values(4)
    real(wp), intent(out) :: flops
    integer, intent(out) :: status
    values = 0
    flops = 0.0_wp
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    associate (id => instance(handle))
      values = [id%infog(1), id%infog(2), id%infog(7), id%infog(29)]
      flops = id%rinfog(3)
    end associate
    status = 0
  end subroutine solver_info

  !> Set MUMPS control ICNTL(index) = value (advanced use: ordering, refinement, memory).
  subroutine solver_set_control(handle, index, value, status)
    integer, intent(in) :: handle, index, value
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    if (index < 1 .or. index > size(instance(handle)%icntl)) then
      status = status_size_mismatch
      return
    end if
    instance(handle)%icntl(index) = value
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
    if (index < 1 .or. index > size(instance(handle)%cntl)) then
      status = status_size_mismatch
      return
    end if
    instance(handle)%cntl(index) = value
    status = 0
  end subroutine solver_set_real_control

  !> Use the pivot order perm for the next analyses (MUMPS ICNTL(7) = 1): perm(i) is the
  !> position (1-based) of variable i in the pivot order.
  subroutine solver_set_ordering(handle, n, perm, status)
    integer, intent(in) :: handle, n, perm(n)
    integer, intent(out) :: status
    if (.not. valid_handle(handle)) then
      status = status_bad_handle
      return
    end if
    associate (id => instance(handle))
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
    call release_arrays(handle)
    associate (id => instance(handle))
      if (associated(id%perm_in)) deallocate (id%perm_in)
      id%job = -2
      call dmumps(id)
      status = id%infog(1)
    end associate
    in_use(handle) = .false.
    analysed(handle) = .false.
    factorized(handle) = .false.
  end subroutine solver_destroy

  subroutine release_arrays(handle)
    integer, intent(in) :: handle
    associate (id => instance(handle))
      if (associated(id%irn)) deallocate (id%irn)
      if (associated(id%jcn)) deallocate (id%jcn)
      if (associated(id%a)) deallocate (id%a)
      if (associated(id%rhs)) deallocate (id%rhs)
    end associate
  end subroutine release_arrays

end module ddpy_linear_solver
