!> TEMPORARY stand-in for the material module (branch `material` provides the real one):
!> isotropic linear elasticity behind the agreed interface, so the solid can be built and
!> tested. Replaced by the Hill'48 + Swift/Voce return mapping on merge.
module ddpy_material
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: material_update

  !> Length of the property vector: (1) E, (2) nu, (3:8) Hill F, G, H, L, M, N,
  !> (9) hardening (1 Swift, 2 Voce), (10:12) Swift K, eps0, n / Voce Y0, Q, b.
  integer, parameter, public :: material_prop_count = 16

contains

  !> Stress update over a strain increment (Voigt 11, 22, 33, 12, 23, 31, engineering
  !> shears, material axes): here linear elastic, stress = stress_old + D : increment.
  pure subroutine material_update(props, stress_old, ep_old, strain_increment, stress, ep, &
                                  tangent, plastic, status)
    real(wp), intent(in) :: props(material_prop_count), stress_old(6), ep_old, &
                            strain_increment(6)
    real(wp), intent(out) :: stress(6), ep, tangent(6, 6)
    logical, intent(out) :: plastic
    integer, intent(out) :: status
    real(wp) :: lambda, mu
    integer :: i
    lambda = props(1)*props(2)/((1.0_wp + props(2))*(1.0_wp - 2.0_wp*props(2)))
    mu = 0.5_wp*props(1)/(1.0_wp + props(2))
    tangent = 0.0_wp
    tangent(1:3, 1:3) = lambda
    do i = 1, 3
      tangent(i, i) = lambda + 2.0_wp*mu
      tangent(i + 3, i + 3) = mu
    end do
    stress = stress_old + matmul(tangent, strain_increment)
    ep = ep_old
    plastic = .false.
    status = 0
  end subroutine material_update

end module ddpy_material
