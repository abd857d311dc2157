!> Sparse matrix helpers of the Newton loop.
!>
!> The assembly writes the Jacobian as coordinates with duplicates (one entry per element
!> contribution, so that threads never write to the same place). The products of the Krylov
!> solver need it with the duplicates summed, once per GMRES call: on the paper's bending
!> blank 11.7 million coordinates into 5.7 million entries. Every entry gathers its own
!> contributions (ddpy.core.linalg.row_structure lists them), in parallel; a scatter over
!> the coordinates would run on one thread.
module ddpy_sparse
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: sum_duplicates

contains

  !> data(i) = sum of values(sources(k) + 1) over k = starts(i) + 1 .. starts(i + 1):
  !> sources lists, entry after entry, the 0-based positions of each entry's contributions.
  subroutine sum_duplicates(n_values, n_data, values, sources, starts, data)
    integer, intent(in) :: n_values, n_data
    real(wp), intent(in) :: values(n_values)
    integer, intent(in) :: sources(*), starts(n_data + 1)
    real(wp), intent(out) :: data(n_data)
    integer :: i, k
    real(wp) :: total
    !$omp parallel do schedule(static) private(k, total)
    do i = 1, n_data
      total = 0.0_wp
      do k = starts(i) + 1, starts(i + 1)
        total = total + values(sources(k) + 1)
      end do
      data(i) = total
    end do
    !$omp end parallel do
  end subroutine sum_duplicates

end module ddpy_sparse
