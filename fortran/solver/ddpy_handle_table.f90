!> The core's one handle table: everything the core keeps between calls, each behind an
!> integer handle that Python holds. An entry is free or holds one of: a MUMPS instance
!> (ddpy_linear_solver, with its process's place among the MPI processes there), a blank
!> (a mesh with its element kind and material, ddpy_blank), a tool surface with its
!> search structures (ddpy_search_surface), or a forming problem with the answer of its
!> last increment trial (ddpy_forming_problem). This module's table, with the process's
!> place among the MPI processes, is the core's only state; every other entry point is a
!> function of its arguments.
module ddpy_handle_table
  use iso_fortran_env, only: int64
  use ddpy_blank, only: blank_mesh
  use ddpy_search_surface, only: search_surface
  use ddpy_forming_problem, only: forming_problem, increment_answer, increment_report
  implicit none
  private
  public :: table_entry, table, max_handles, claim_handle, valid_handle, free_entry

  include 'dmumps_struc.h'
  include 'smumps_struc.h'

  !> Handles that may live at the same time, of all kinds together.
  integer, parameter :: max_handles = 1024
  !> Why an entry point that takes or makes a handle refused (its status; 0: done): the
  !> handle holds no such thing, an array's size does not fit, an index out of range or
  !> out of order, the table is full, a value out of range, a call before the ones it
  !> needs (a problem's increment before its settings, state, tools and law are set).
  integer, parameter, public :: refusal_handle = 1, refusal_size = 2, refusal_index = 3, &
                                refusal_full = 4, refusal_value = 5, refusal_order = 6
  !> What an entry holds.
  integer, parameter, public :: entry_free = 0, entry_solver = 1, entry_blank = 2, &
                                entry_surface = 3, entry_problem = 4

  !> One entry. A MUMPS instance stays where it was allocated until freed (MUMPS keeps its
  !> own state inside it).
  type :: table_entry
    integer :: holds = entry_free
    type(dmumps_struc), allocatable :: mumps
    !> A single-precision solver's instance (solver_create's precision): it factorizes
    !> and solves, with the structure, controls and pivot order of mumps, which it mirrors.
    type(smumps_struc), allocatable :: single
    logical :: analysed = .false., factorized = .false.
    !> Entries of the factorization's workspace to give MUMPS (its S, as large as MUMPS took
    !> for the last factorization of its own; 0: none known yet).
    integer(int64) :: workspace = 0
    type(blank_mesh), allocatable :: blank
    type(search_surface), allocatable :: surface
    type(forming_problem), allocatable :: problem
    type(increment_answer), allocatable :: answer
    type(increment_report), allocatable :: report
  end type table_entry

  type(table_entry), target, save :: table(max_handles)

  !> The process's place among the MPI processes (ddpy_linear_solver): MPI not started,
  !> running, or finished (stopped for good); its rank and the number of processes.
  integer, parameter, public :: mpi_not_started = 0, mpi_running = 1, mpi_finished = 2
  type, public :: process_world
    integer :: state = mpi_not_started, rank = 0, size = 1
  end type process_world
  type(process_world), save, public :: world

contains

  !> The first free handle, marked as holding what (0 when the table is full); or, with
  !> handle > 0 (the MPI ranks > 0 mirror rank 0's solvers), that handle.
  subroutine claim_handle(what, handle)
    integer, intent(in) :: what
    integer, intent(inout) :: handle
    integer :: h
    if (handle > 0 .and. handle <= max_handles) then
      table(handle)%holds = what
      return
    end if
    handle = 0
    do h = 1, max_handles
      if (table(h)%holds == entry_free) then
        handle = h
        table(h)%holds = what
        return
      end if
    end do
  end subroutine claim_handle

  !> Whether handle is in the table and holds what.
  logical function valid_handle(handle, what)
    integer, intent(in) :: handle, what
    valid_handle = .false.
    if (handle < 1 .or. handle > max_handles) return
    valid_handle = table(handle)%holds == what
  end function valid_handle

  !> Free what the entry holds besides a MUMPS instance (which ddpy_linear_solver ends
  !> first, collectively), and mark it free.
  subroutine free_entry(handle)
    integer, intent(in) :: handle
    if (allocated(table(handle)%mumps)) deallocate(table(handle)%mumps)
    if (allocated(table(handle)%single)) deallocate(table(handle)%single)
    if (allocated(table(handle)%blank)) deallocate(table(handle)%blank)
    if (allocated(table(handle)%surface)) deallocate(table(handle)%surface)
    if (allocated(table(handle)%problem)) deallocate(table(handle)%problem)
    if (allocated(table(handle)%answer)) deallocate(table(handle)%answer)
    if (allocated(table(handle)%report)) deallocate(table(handle)%report)
    table(handle)%analysed = .false.
    table(handle)%factorized = .false.
    table(handle)%holds = entry_free
  end subroutine free_entry

end module ddpy_handle_table
